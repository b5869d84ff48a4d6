#include "core/study_report_export.hpp"

#include "hattr/report/design_analysis.hpp"
#include "hattr/report/study_report.hpp"

namespace hattr::studio {

std::filesystem::path reportFolderFor(const std::filesystem::path& db_file) {
  return db_file.parent_path() / (db_file.stem().string() + "-report");
}

ReviewReport writeReviewReport(const session::StudyDatabase& db, const std::filesystem::path& db_file) {
  // A design of groups and sessions, one learner, or an incomplete paper's design: the design's
  // analysis, and each completed trial's costs.
  if (!report::chooseAnalysis(db).balanced) {
    const report::DesignAnalysis design = report::analyzeDesign(db);
    std::vector<report::TrialCost> costs;
    for (const auto& s : design.scores) costs.push_back({s.trial_id, s.subject, s.strategy, s.trial, s.score, s.disturbed});
    return {.html = report::writeDesignReport(db, design, reportFolderFor(db_file)), .costs = std::move(costs)};
  }
  report::StudyAnalysis analysis = report::analyzeStudy(db);
  // Designated initializers run in order: the report is written before its costs are moved out.
  return {.html = report::writeStudyReport(db, analysis, reportFolderFor(db_file)), .costs = std::move(analysis.costs)};
}

}  // namespace hattr::studio
