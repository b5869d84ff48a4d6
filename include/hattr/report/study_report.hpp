#pragma once
/// The study report: a self-contained report.html (inline SVG, no scripts, no network) and a
/// report.md with the same content (figures as SVG files beside it): the design, the ANOVA
/// tables, Table 1, per-mode mean and variance for both metrics (the paper's figures 5 and
/// 6), the expert's and trainees' haptic profiles over time (figure 3), recall trajectories
/// over the expert's, and conclusions that state only what the numbers show.

#include <filesystem>

#include "hattr/report/study_analysis.hpp"

namespace hattr::report {

/// What writeStudyReport writes in OUT (the figures folder with its SVGs inside).
inline const std::vector<std::string> kStudyReportFiles{"report.html", "report.md", "figures"};
/// Writes OUT/report.html, OUT/report.md and OUT/figures/*.svg (OUT is created; existing
/// report files are replaced). Returns the path of report.html.
std::filesystem::path writeStudyReport(const session::StudyDatabase& db, const StudyAnalysis& analysis,
                                       const std::filesystem::path& out_dir);

/// The conclusions paragraph alone (tested: it must follow the numbers).
std::vector<std::string> conclusions(const StudyAnalysis& analysis, double alpha = 0.05);

}  // namespace hattr::report
