#include "core/study_report_export.hpp"

#include "hattr/report/design_analysis.hpp"
#include "hattr/report/study_report.hpp"

namespace hattr::studio {

std::filesystem::path reportFolderFor(const std::filesystem::path& db_file) {
  return db_file.parent_path() / (db_file.stem().string() + "-report");
}

ReviewReport writeReviewReport(const session::StudyDatabase& db, const std::filesystem::path& db_file) {
  const std::filesystem::path folder = reportFolderFor(db_file);
  // A design of groups and sessions, one learner, or an incomplete paper's design: the design's
  // analysis, its tables and each trial's costs (the tree shows those it leaves out too).
  if (!report::chooseAnalysis(db).balanced) {
    const report::DesignAnalysis design = report::analyzeDesign(db);
    report::writeDesignCsv(design, folder);
    std::vector<report::TrialCost> costs;
    for (const auto* list : {&design.scores, &design.left_out}) {
      for (const auto& s : *list) costs.push_back({s.trial_id, s.subject, s.strategy, s.trial, s.score, s.disturbed});
    }
    return {.html = report::writeDesignReport(db, design, folder), .costs = std::move(costs)};
  }
  // The paper's complete design: its tables and the long table of every trial, as the CLI's.
  report::StudyAnalysis analysis = report::analyzeStudy(db);
  report::writeAnalysisCsv(analysis, folder);
  report::writeTrialsCsv(db, analysis, analysis.options, folder / "trials.csv");
  // Designated initializers run in order: the report is written before its costs are moved out.
  return {.html = report::writeStudyReport(db, analysis, folder), .costs = std::move(analysis.costs)};
}

}  // namespace hattr::studio
