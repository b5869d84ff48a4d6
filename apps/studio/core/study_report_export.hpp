#pragma once
/// The analysis report of a study from Review: report::analyzeStudy and
/// report::writeStudyReport with the CSV tables of `hattr study report` (a design of groups and
/// sessions: report::analyzeDesign, report::writeDesignReport and its tables) into a folder
/// next to the database (<db stem>-report/).
/// GUI thread (it takes a moment: DTW over every recall trial); throws InputError when the
/// study is not complete enough (the library's message names the missing trials).

#include <filesystem>

#include "hattr/report/study_analysis.hpp"
#include "hattr/session/study_database.hpp"

namespace hattr::studio {

/// <folder of db_file>/<stem of db_file>-report
std::filesystem::path reportFolderFor(const std::filesystem::path& db_file);

/// A report written from Review: its page and the per-trial costs it was made from.
struct ReviewReport {
  std::filesystem::path html;
  std::vector<report::TrialCost> costs;
};

/// Analyzes the study in `db` (opened from `db_file`) and writes its report into
/// reportFolderFor(db_file).
ReviewReport writeReviewReport(const session::StudyDatabase& db, const std::filesystem::path& db_file);

}  // namespace hattr::studio
