#include "core/study_report_export.hpp"

#include "hattr/report/study_analysis.hpp"
#include "hattr/report/study_report.hpp"

namespace hattr::studio {

std::filesystem::path reportFolderFor(const std::filesystem::path& db_file) {
  return db_file.parent_path() / (db_file.stem().string() + "-report");
}

std::filesystem::path writeReviewReport(const session::StudyDatabase& db, const std::filesystem::path& db_file) {
  const report::StudyAnalysis analysis = report::analyzeStudy(db);
  return report::writeStudyReport(db, analysis, reportFolderFor(db_file));
}

}  // namespace hattr::studio
