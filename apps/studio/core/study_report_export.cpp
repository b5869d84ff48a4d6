#include "core/study_report_export.hpp"

#include "hattr/report/study_report.hpp"

namespace hattr::studio {

std::filesystem::path reportFolderFor(const std::filesystem::path& db_file) {
  return db_file.parent_path() / (db_file.stem().string() + "-report");
}

ReviewReport writeReviewReport(const session::StudyDatabase& db, const std::filesystem::path& db_file) {
  report::StudyAnalysis analysis = report::analyzeStudy(db);
  // Designated initializers run in order: the report is written before its costs are moved out.
  return {.html = report::writeStudyReport(db, analysis, reportFolderFor(db_file)), .costs = std::move(analysis.costs)};
}

}  // namespace hattr::studio
