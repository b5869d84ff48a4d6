#include "hattr/report/paper_comparison.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

namespace hattr::report {
namespace {

constexpr const char* kModes[] = {"BASIC", "PCONTROL", "ALPHA"};

// The paper's protocol (section 5): 10 subjects, 11 training trials with assistance and the
// reference, then 11 recall trials without either, 10 of them analyzed (section 6).
constexpr std::size_t kPaperSubjects = 10;
constexpr int kPaperTrainingTrials = 11;
constexpr int kPaperRecallTrials = 11;
constexpr std::size_t kPaperAnalyzedRecallTrials = 10;

std::string metricName(PaperMetric metric) { return metric == PaperMetric::kShape ? "shape" : "haptic profile"; }

const MetricResult& resultFor(const StudyAnalysis& analysis, PaperMetric metric) {
  return metric == PaperMetric::kShape ? analysis.trajectory : analysis.force;
}

const analysis::AnovaRow* findSource(const analysis::AnovaTable& table, const std::string& source) {
  for (const auto& row : table.rows) {
    if (row.source == source) return &row;
  }
  return nullptr;
}

std::string pText(double p) { return p < 0.001 ? "p < 0.001" : fmt::format("p = {:.3f}", p); }

/// "significant (p = 0.012)" or "not significant (p = 0.43)".
std::string significanceText(double p, double alpha) {
  return fmt::format("{}significant ({})", p < alpha ? "" : "not ", pText(p));
}

Agreement agreementOf(bool same) { return same ? Agreement::kAgrees : Agreement::kDiffers; }

/// Where the study's protocol is not the paper's.
std::vector<std::string> protocolDifferences(const session::StudyDefinition& study, std::size_t subjects) {
  std::vector<std::string> out;
  const session::Protocol& p = study.protocol;
  if (subjects != kPaperSubjects) out.push_back(fmt::format("{} subjects (the paper: {})", subjects, kPaperSubjects));
  if (p.training_trials != kPaperTrainingTrials) {
    out.push_back(fmt::format("{} training trials per mode (the paper: {})", p.training_trials, kPaperTrainingTrials));
  }
  if (p.recall_trials != kPaperRecallTrials) {
    out.push_back(fmt::format("{} recall trials per mode (the paper: {})", p.recall_trials, kPaperRecallTrials));
  }
  if (const auto analyzed = session::analyzedRecallTrials(p); analyzed.size() != kPaperAnalyzedRecallTrials) {
    out.push_back(fmt::format("{} recall trials analyzed per mode (the paper: {})", analyzed.size(),
                              kPaperAnalyzedRecallTrials));
  }
  if (!p.training.guidance || !p.training.show_reference) {
    out.push_back("training without the mode's assistance or without the reference (the paper: both)");
  }
  if (p.recall.guidance || p.recall.show_reference) {
    out.push_back("recall with assistance or with the reference shown (the paper: neither)");
  }
  return out;
}

/// Section 6's per-mode ANOVA statements.
void addAnovaRows(const StudyAnalysis& analysis, double alpha, std::vector<ComparisonRow>& rows) {
  for (const PaperAnovaFinding& f : paperAnovaFindings()) {
    ComparisonRow row;
    row.point = fmt::format("{}, {}: {}", metricName(f.metric), f.mode,
                            f.factor == "trial" ? "effect of training (recall trial)" : "difference between subjects");
    row.source = "section 6";
    row.paper = f.significant ? fmt::format("significant ({})", f.p_text) : "not significant";
    const MetricResult& m = resultFor(analysis, f.metric);
    const auto table = m.per_mode.find(f.mode);
    const analysis::AnovaRow* r = table == m.per_mode.end() ? nullptr : findSource(table->second, f.factor);
    if (r == nullptr || !std::isfinite(r->p)) {
      row.hattr = "not computed (too few trials or subjects)";
    } else {
      row.hattr = significanceText(r->p, alpha);
      row.agreement = agreementOf((r->p < alpha) == f.significant);
    }
    rows.push_back(std::move(row));
  }
}

/// Section 6: "ANOVA suggested that none of the modes have any significant impact on
/// character shape matching".
void addModeEffectRow(const StudyAnalysis& analysis, double alpha, std::vector<ComparisonRow>& rows) {
  ComparisonRow row{.point = "shape: effect of the training mode (mode × subject ANOVA)",
                    .source = "section 6",
                    .paper = "not significant",
                    .hattr = "not computed"};
  if (const analysis::AnovaRow* mode = findSource(analysis.trajectory.overall, "mode"); mode && std::isfinite(mode->p)) {
    row.hattr = significanceText(mode->p, alpha);
    row.agreement = agreementOf(mode->p >= alpha);
  }
  rows.push_back(std::move(row));
}

/// The mode with the least (or most) value among the paper's three, and the values as text.
struct Extreme {
  std::string mode;
  std::string values;
};
Extreme extremeOf(const std::map<std::string, double>& by_mode, bool least) {
  Extreme e;
  double best = least ? INFINITY : -INFINITY;
  std::vector<std::string> parts;
  for (const char* mode : kModes) {
    const auto it = by_mode.find(mode);
    if (it == by_mode.end()) continue;
    parts.push_back(fmt::format("{} {:.4g}", mode, it->second));
    if (least ? it->second < best : it->second > best) {
      best = it->second;
      e.mode = mode;
    }
  }
  e.values = fmt::format("{}", fmt::join(parts, ", "));
  return e;
}

/// Section 6: the overall inter-subject variance was least for ALPHA (both metrics).
void addVarianceRow(const StudyAnalysis& analysis, PaperMetric metric, std::vector<ComparisonRow>& rows) {
  std::map<std::string, double> by_mode;
  for (const auto& v : resultFor(analysis, metric).inter_subject) by_mode[v.level] = v.variance;
  const Extreme least = extremeOf(by_mode, true);
  rows.push_back({.point = fmt::format("{}: least inter-subject variance", metricName(metric)),
                  .source = "section 6",
                  .paper = "ALPHA",
                  .hattr = fmt::format("{} ({})", least.mode, least.values),
                  .agreement = agreementOf(least.mode == "ALPHA")});
}

/// Abstract and section 7 ("superior results"; "BASIC ... showed the worst performance"),
/// read as the lowest and the highest mean recall cost.
void addMeanRows(const StudyAnalysis& analysis, PaperMetric metric, std::vector<ComparisonRow>& rows) {
  std::map<std::string, double> by_mode;
  for (const auto& s : resultFor(analysis, metric).per_mode_stats) by_mode[s.a_level] = s.stats.mean;
  const Extreme best = extremeOf(by_mode, true);
  const Extreme worst = extremeOf(by_mode, false);
  rows.push_back({.point = fmt::format("{}: best mode (lowest mean recall cost)", metricName(metric)),
                  .source = "abstract, section 7",
                  .paper = "ALPHA (\"superior\")",
                  .hattr = fmt::format("{} ({})", best.mode, best.values),
                  .agreement = agreementOf(best.mode == "ALPHA")});
  rows.push_back({.point = fmt::format("{}: worst mode (highest mean recall cost)", metricName(metric)),
                  .source = "section 7",
                  .paper = "BASIC (\"the worst performance\")",
                  .hattr = fmt::format("{} ({})", worst.mode, worst.values),
                  .agreement = agreementOf(worst.mode == "BASIC")});
}

/// How many subjects had each mode as their best, and the mode most of them had (empty on a tie).
struct Tally {
  std::map<std::string, int> count;
  std::string most;
  std::string text() const {
    std::vector<std::string> parts;
    for (const char* mode : kModes) parts.push_back(fmt::format("{} {}", mode, count.count(mode) ? count.at(mode) : 0));
    return fmt::format("{}", fmt::join(parts, ", "));
  }
};
Tally tallyOf(const std::vector<std::string>& best_modes) {
  Tally t;
  for (const auto& mode : best_modes) ++t.count[mode];
  int top = 0;
  for (const auto& [mode, n] : t.count) {
    if (n > top) {
      top = n;
      t.most = mode;
    } else if (n == top) {
      t.most.clear();
    }
  }
  return t;
}

/// Table 1: each subject's best mode, compared as counts (the simulated subjects are not the
/// paper's people); agrees when the same mode is the best for the most subjects.
void addTable1Row(const StudyAnalysis& analysis, PaperMetric metric, std::vector<ComparisonRow>& rows) {
  std::vector<std::string> paper_modes, hattr_modes;
  for (const auto& r : paperTable1()) paper_modes.push_back(metric == PaperMetric::kShape ? r.shape : r.haptic_profile);
  for (const auto& [subject, mode] : resultFor(analysis, metric).best_mode) hattr_modes.push_back(mode);
  const Tally paper = tallyOf(paper_modes);
  const Tally hattr = tallyOf(hattr_modes);
  rows.push_back({.point = fmt::format("{}: subjects whose best mode it is", metricName(metric)),
                  .source = "Table 1",
                  .paper = fmt::format("{} of {}", paper.text(), paper_modes.size()),
                  .hattr = fmt::format("{} of {}", hattr.text(), hattr_modes.size()),
                  .agreement = agreementOf(!hattr.most.empty() && hattr.most == paper.most)});
}

}  // namespace

const std::vector<PaperAnovaFinding>& paperAnovaFindings() {
  using enum PaperMetric;
  static const std::vector<PaperAnovaFinding> findings = {
      // "Character Shape Match: ... For the BASIC mode, there was insignificant effect of
      // training and significant difference between performances of the subjects (p < 0.001).
      // For the PCONTROL mode there was insignificant effect of training and there was no
      // significant difference between performances of subjects. For the ALPHA mode there was
      // insignificant effect of training and there was no significant difference ..."
      {kShape, "BASIC", "trial", false, ""},
      {kShape, "BASIC", "subject", true, "p < 0.001"},
      {kShape, "PCONTROL", "trial", false, ""},
      {kShape, "PCONTROL", "subject", false, ""},
      {kShape, "ALPHA", "trial", false, ""},
      {kShape, "ALPHA", "subject", false, ""},
      // "Haptic Profile Shape Match: ... For the BASIC mode, there was insignificant effect of
      // training and significant difference between performances of the subjects (p < 0.001).
      // For the PCONTROL mode there was a significant effect of training (p < .003) and there
      // was no significant difference between performances of subjects. For the ALPHA mode
      // there was marginally significant effect of training (p < 0.01) and the trainees
      // performed similarly."
      {kHapticProfile, "BASIC", "trial", false, ""},
      {kHapticProfile, "BASIC", "subject", true, "p < 0.001"},
      {kHapticProfile, "PCONTROL", "trial", true, "p < 0.003"},
      {kHapticProfile, "PCONTROL", "subject", false, ""},
      {kHapticProfile, "ALPHA", "trial", true, "p < 0.01, \"marginally\""},
      {kHapticProfile, "ALPHA", "subject", false, ""},
  };
  return findings;
}

const std::vector<PaperTable1Row>& paperTable1() {
  static const std::vector<PaperTable1Row> table = {
      {1, "ALPHA", "ALPHA"},    {2, "PCONTROL", "ALPHA"}, {3, "ALPHA", "PCONTROL"}, {4, "ALPHA", "BASIC"},
      {5, "ALPHA", "PCONTROL"}, {6, "BASIC", "PCONTROL"}, {7, "ALPHA", "BASIC"},    {8, "ALPHA", "PCONTROL"},
      {9, "ALPHA", "BASIC"},    {10, "BASIC", "ALPHA"},
  };
  return table;
}

std::string_view agreementName(Agreement agreement) {
  switch (agreement) {
    case Agreement::kAgrees:
      return "agrees";
    case Agreement::kDiffers:
      return "differs";
    case Agreement::kNotMeasured:
      break;
  }
  return "not measured";
}

int PaperComparison::count(Agreement agreement) const {
  return static_cast<int>(std::count_if(rows.begin(), rows.end(), [agreement](const auto& r) { return r.agreement == agreement; }));
}

PaperComparison compareWithPaper(const session::StudyDefinition& study, std::size_t subject_count,
                                 const StudyAnalysis& analysis, double alpha) {
  PaperComparison out;
  // Only a study of the paper's skill (the Tamil ந: the built-in glyph "na", or the character)
  // in the paper's three modes can be set beside it.
  if (study.skill != "na" && study.skill != "ந") return out;
  for (const char* mode : kModes) {
    const bool present = std::any_of(study.modes.begin(), study.modes.end(),
                                     [mode](guidance::TrainingMode m) { return guidance::modeName(m) == mode; });
    if (!present) return out;
  }
  out.applicable = true;
  out.alpha = alpha;
  out.protocol_differences = protocolDifferences(study, subject_count);
  addAnovaRows(analysis, alpha, out.rows);
  addModeEffectRow(analysis, alpha, out.rows);
  for (const PaperMetric metric : {PaperMetric::kShape, PaperMetric::kHapticProfile}) {
    addVarianceRow(analysis, metric, out.rows);
    addTable1Row(analysis, metric, out.rows);
    addMeanRows(analysis, metric, out.rows);
  }
  return out;
}

nlohmann::json comparisonToJson(const PaperComparison& comparison) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : comparison.rows) {
    rows.push_back({{"point", r.point}, {"source", r.source}, {"paper", r.paper}, {"hattr", r.hattr},
                    {"agreement", agreementName(r.agreement)}});
  }
  return {{"applicable", comparison.applicable},
          {"alpha", comparison.alpha},
          {"protocol_differences", comparison.protocol_differences},
          {"agrees", comparison.count(Agreement::kAgrees)},
          {"differs", comparison.count(Agreement::kDiffers)},
          {"not_measured", comparison.count(Agreement::kNotMeasured)},
          {"rows", rows}};
}

std::vector<std::string> comparisonText(const PaperComparison& comparison) {
  std::vector<std::string> out;
  if (!comparison.applicable) {
    out.emplace_back("The paper trains the Tamil ந (skill \"na\") in BASIC, PCONTROL and ALPHA; this study does not, so "
                     "it is not set beside the paper.");
    return out;
  }
  out.push_back(fmt::format("The paper next to this study: {} points agree, {} differ, {} not measured (significance at "
                            "α = {}; the paper's statements are in hattr's source, src/report/paper_comparison.cpp).",
                            comparison.count(Agreement::kAgrees), comparison.count(Agreement::kDiffers),
                            comparison.count(Agreement::kNotMeasured), comparison.alpha));
  for (const auto& d : comparison.protocol_differences) out.push_back("  protocol differs from the paper's: " + d);
  for (const auto& r : comparison.rows) {
    out.push_back(fmt::format("  [{}] {} — {}", agreementName(r.agreement), r.point, r.source));
    out.push_back(fmt::format("      paper: {}; this study: {}", r.paper, r.hattr));
  }
  return out;
}

}  // namespace hattr::report
