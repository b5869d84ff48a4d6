#include "hattr/report/study_report.hpp"

#include "hattr/analysis/learning_curve.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>
#include <utility>

#include <fmt/format.h>

#include "hattr/analysis/studentized_range.hpp"
#include "hattr/core/units.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/report/paper_comparison.hpp"
#include "report_document.hpp"
#include "svg_plot_internal.hpp"

namespace hattr::report {
namespace {

using detail::Document;
using detail::escape;
using detail::g;
using detail::meanWithCi;
using detail::p;
using detail::pIs;
using detail::Series;
using detail::SvgPlot;
using detail::Table;

/// One colour per mode, the same in every figure.
std::string modeColour(const std::string& mode) {
  // One colour per strategy (the paper's three first), in TrainingMode order; grey for another name.
  static constexpr std::array<const char*, 14> kColours{"#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                                                        "#e377c2", "#bcbd22", "#17becf", "#ff7f0e", "#393b79",
                                                        "#637939", "#8c6d31", "#843c39", "#7b4173"};
  static_assert(kColours.size() == static_cast<std::size_t>(guidance::kLastMode) + 1);
  for (int m = 0; m <= static_cast<int>(guidance::kLastMode); ++m) {
    if (guidance::modeName(static_cast<guidance::TrainingMode>(m)) == mode) return kColours[static_cast<std::size_t>(m)];
  }
  return "#7f7f7f";
}

/// Where `mode` stands in the study file's order (StudyAnalysis::modes, the paper's: BASIC,
/// PCONTROL, ALPHA), for every table, legend and bar; a mode the study does not name goes last.
std::size_t modeRank(const std::vector<std::string>& order, const std::string& mode) {
  return static_cast<std::size_t>(std::find(order.begin(), order.end(), mode) - order.begin());
}

/// A recall cost of one metric: "trajectory" or "force".
double costOf(const TrialCost& c, const std::string& metric) { return metric == "trajectory" ? c.trajectory() : c.forceProfile(); }

/// Each subject's mean recall cost of one metric in one mode (subjects in id order).
std::map<std::string, double> subjectMeans(const std::vector<TrialCost>& costs, const std::string& mode,
                                           const std::string& metric) {
  std::map<std::string, std::vector<double>> values;
  for (const TrialCost& c : costs) {
    if (c.mode == mode) values[c.subject].push_back(costOf(c, metric));
  }
  std::map<std::string, double> means;
  for (const auto& [subject, v] : values) means[subject] = meanWithCi(v).first;
  return means;
}

Table anovaTable(const analysis::AnovaTable& t) {
  Table out{{"source", "df", "sum sq", "mean sq", "F", "p", "partial η²", "tested against"}, {}};
  for (const auto& r : t.rows) {
    out.rows.push_back({r.source, fmt::format("{}", r.df), g(r.sum_sq), g(r.mean_sq), g(r.f), p(r.p), g(r.partial_eta_sq),
                        r.error_term});
  }
  return out;
}

const analysis::AnovaRow* findRow(const analysis::AnovaTable& t, const std::string& source) {
  for (const auto& r : t.rows) {
    if (r.source == source) return &r;
  }
  return nullptr;
}

std::string metricUnit(const std::string& metric) {
  return metric == "trajectory" ? "DTW cost of x + y, the shape on the paper (normalized units)"
                                : "DTW cost of fx + fy + fz (normalized units)";
}

}  // namespace

namespace {

/// The least-squares slope of values[i] over the trial numbers 1, 2, ... (0 for fewer than 2).
double slopeOverTrials(const std::vector<double>& values) {
  std::vector<double> n(values.size());
  for (std::size_t i = 0; i < n.size(); ++i) n[i] = static_cast<double>(i + 1);
  const double slope = analysis::linearTrend(n, values).slope;
  return std::isfinite(slope) ? slope : 0.0;
}

/// The modes of a metric's per-mode tables in the study's order (those the study does not name,
/// or all when the order is not known, after, in name order).
std::vector<std::string> inStudyOrder(const StudyAnalysis& a, const MetricResult& m) {
  std::vector<std::string> order;
  for (const std::string& mode : a.modes) {
    if (m.per_mode.contains(mode)) order.push_back(mode);
  }
  for (const auto& [mode, table] : m.per_mode) {
    if (std::find(order.begin(), order.end(), mode) == order.end()) order.push_back(mode);
  }
  return order;
}
}  // namespace

std::vector<std::string> conclusions(const StudyAnalysis& a, double alpha) {
  std::vector<std::string> out;
  for (const MetricResult* m : {&a.trajectory, &a.force}) {
    const std::string what = m->metric == "trajectory" ? "trajectory (shape)" : "haptic-profile (force)";
    // Which mode had the lowest mean recall cost, and did mode matter?
    const auto best = std::min_element(m->per_mode_stats.begin(), m->per_mode_stats.end(),
                                       [](const auto& x, const auto& y) { return x.stats.mean < y.stats.mean; });
    const analysis::AnovaRow* mode = findRow(m->overall, "mode");
    const analysis::AnovaRow* error = mode ? findRow(m->overall, mode->error_term) : nullptr;
    if (mode && error && best != m->per_mode_stats.end()) {
      const bool significant = mode->p < alpha;
      out.push_back(fmt::format(
          "On the {} metric, the lowest mean recall cost was with {} ({:.4g}); the effect of mode was {}significant "
          "at α = {} (F({}, {}) = {:.3g}, {}).",
          what, best->a_level, best->stats.mean, significant ? "" : "not ", alpha, mode->df, error->df, mode->f, pIs(mode->p)));
    }
    // Subjects differ?
    if (const analysis::AnovaRow* subject = findRow(m->overall, "subject"); subject && std::isfinite(subject->p)) {
      out.push_back(fmt::format("Subjects differed {}significantly on the {} metric ({}).",
                                subject->p < alpha ? "" : "not ", what, pIs(subject->p)));
    }
    // Training effect within each mode: the trial factor of the per-mode ANOVA, with its
    // direction (the least-squares slope of the mean cost over the recall trials): costs that
    // rise over recall are forgetting or fatigue, not learning.
    std::vector<std::string> trained;
    for (const std::string& mode_name : inStudyOrder(a, *m)) {
      const analysis::AnovaRow* trial = findRow(m->per_mode.at(mode_name), "trial");
      if (!trial || !(trial->p < alpha)) continue;
      const auto means = m->mean_by_trial.find(mode_name);
      const double slope = means == m->mean_by_trial.end() ? 0.0 : slopeOverTrials(means->second);
      trained.push_back(fmt::format("{} ({}, {:+.3g} per trial: {})", mode_name, pIs(trial->p), slope,
                                    slope > 0.0 ? "costs rose over the recall trials, forgetting or fatigue, not learning"
                                                : "costs fell over the recall trials"));
    }
    out.push_back(trained.empty()
                      ? fmt::format("No mode showed a significant change over the recall trials on the {} metric.", what)
                      : fmt::format("Recall trial number had a significant effect on the {} metric in: {}.", what,
                                    fmt::join(trained, "; ")));
  }
  return out;
}

/// The report's opening in plain words: what was compared, the mode effect with its size and
/// the differences' intervals, the trend over recall, what the numbers do not show.
std::vector<std::string> paperSummary(const session::StudyDefinition& study, const StudyAnalysis& a,
                                      std::size_t subjects, const std::string& reason) {
  std::vector<std::string> out;
  out.push_back(fmt::format("Compared: the training modes {}, each of {} subjects trying each, on recall trials written "
                            "{}. Analysis: {}.",
                            fmt::join(a.modes, ", "), subjects,
                            study.protocol.recall.guidance ? "with the mode's guidance" : "without guidance", reason));
  const MetricResult& m = a.trajectory;
  const analysis::AnovaRow* mode = findRow(m.overall, "mode");
  const analysis::AnovaRow* error = mode ? findRow(m.overall, mode->error_term) : nullptr;
  if (mode != nullptr && error != nullptr) {
    const bool differed = mode->p < 0.05;
    out.push_back(fmt::format("{} (F({}, {}) = {:.3g}, {}; partial η² = {:.2f}, the share of the variation between modes "
                              "and its error that the modes explain).",
                              differed ? "The shape cost of the recall trials differed between the modes"
                                       : "No mode gave a shape cost the test can tell from the others'",
                              mode->df, error->df, mode->f, pIs(mode->p), mode->partial_eta_sq));
  }
  if (m.tukey) {
    std::vector<std::string> pairs;
    for (const auto& c : m.tukey->comparisons) {
      pairs.push_back(fmt::format("{} {:+.3g} (95 % CI {:.3g} to {:.3g})", c.comparison, c.diff, c.lower, c.upper));
    }
    out.push_back(fmt::format("Differences in mean shape cost between modes (Tukey's intervals; lower is closer to the "
                              "expert): {}.", fmt::join(pairs, "; ")));
  }
  // The trend over the recall trials: the least-squares slope of the mean cost with its interval.
  for (const std::string& mode_name : inStudyOrder(a, m)) {
    const auto means = m.mean_by_trial.find(mode_name);
    if (means == m.mean_by_trial.end()) continue;
    std::vector<double> n;
    for (std::size_t i = 0; i < means->second.size(); ++i) n.push_back(static_cast<double>(i + 1));
    const analysis::LinearTrend trend = analysis::linearTrend(n, means->second);
    if (!std::isfinite(trend.lower) || (trend.lower <= 0.0 && trend.upper >= 0.0)) continue;
    out.push_back(fmt::format("With {}, the mean shape cost {} over the analyzed recall trials ({:+.3g} per trial, 95 % CI "
                              "{:.3g} to {:.3g}){}.",
                              mode_name, trend.slope > 0.0 ? "rose" : "fell", trend.slope, trend.lower, trend.upper,
                              trend.slope > 0.0 ? ": forgetting or fatigue, not learning" : ""));
  }
  out.push_back(fmt::format("What it does not show: whether what was learned lasts (no delayed retention test), nor "
                            "that modes the test cannot tell apart are equal: with {} subjects, small effects go unseen.",
                            subjects));
  return out;
}

namespace {

/// The design section: what was compared and how, each subject's order of modes, which recall
/// trials went in, and the trials the loop disturbed.
void writeDesignSection(const session::StudyDefinition& study, const std::vector<session::SubjectRecord>& subjects,
                        const StudyAnalysis& a, Document& doc) {
  doc.heading("Design");
  doc.paragraph(fmt::format(
      "{} subjects learned the skill \"{}\" in {} modes. Per mode: {} training trials ({}), then {} recall trials ({}). "
      "Device {}, servo rate {} Hz, {} indexing. Costs: {} preprocessing, {} DTW cost, per axis, summed.",
      subjects.size(), study.skill, study.modes.size(), study.protocol.training_trials,
      study.protocol.training.guidance ? "with the mode's guidance, reference shown" : "without guidance",
      study.protocol.recall_trials, study.protocol.recall.show_reference ? "reference shown" : "no guidance, reference hidden",
      study.device, study.rate_hz, guidance::indexingName(study.indexing),
      a.options.normalization == analysis::Normalization::kPaper ? "the paper's" : "z-score/none",
      a.options.cost == analysis::DtwCost::kAbsolute ? "absolute-difference" : "squared"));
  Table orders{{"subject", "participant", "mode order"}, {}};
  for (const auto& s : subjects) {
    std::vector<std::string> names;
    for (const auto m : s.mode_order) names.emplace_back(guidance::modeName(m));
    orders.rows.push_back({s.id, s.spec.participant, fmt::format("{}", fmt::join(names, " → "))});
  }
  doc.table(orders);

  // Which recall trials went in, and the trials the loop disturbed.
  doc.paragraph(fmt::format(
      "Analyzed: recall trials {} of each mode ({} of {}; the paper used 10 of its 11 and does not say which it left "
      "out, hattr leaves out the first by default: protocol.analyzed_recall_trials). The pen height z is scored on its "
      "own (mean DTW cost {:.4g}) and is not part of the shape.",
      fmt::join(a.analyzed_recall_trials, ", "), a.analyzed_recall_trials.size(), study.protocol.recall_trials,
      [&a] {
        double sum = 0.0;
        for (const auto& c : a.costs) sum += c.score.z;
        return a.costs.empty() ? 0.0 : sum / static_cast<double>(a.costs.size());
      }()));
  doc.heading("Disturbed trials", 3);
  if (a.flagged.empty()) {
    doc.paragraph(fmt::format("No analyzed recall trial was disturbed by the servo loop (policy \"{}\").",
                              a.disturbed_policy));
  } else {
    Table flagged{{"subject", "mode", "recall trial", "disturbance", "earlier disturbed attempts", "analyzed"}, {}};
    for (const auto& f : a.flagged) {
      flagged.rows.push_back({f.subject, f.mode, fmt::format("{}", f.trial), f.disturbed,
                              fmt::format("{}", f.disturbed_attempts), f.analyzed ? "yes, flagged" : "no, excluded"});
    }
    doc.paragraph(fmt::format("Policy \"{}\"; {} spare trial{} stood in for excluded ones.", a.disturbed_policy,
                              a.spares_used.size(), a.spares_used.size() == 1 ? "" : "s"));
    doc.table(flagged);
  }
}

/// The paper's findings beside this study's, point by point (nothing when the comparison does
/// not apply to the study).
void writePaperComparison(const session::StudyDefinition& study, std::size_t subject_count, const StudyAnalysis& a,
                          Document& doc) {
  const PaperComparison paper = compareWithPaper(study, subject_count, a);
  if (paper.applicable) {
    doc.heading("The paper next to this study");
    doc.paragraph(fmt::format(
        "What Srimathveeravalli & Kesavadas report (section 6, Table 1, section 7, the abstract) and what this study "
        "measured, point by point: {} agree, {} differ, {} could not be measured. A point agrees when the statement is "
        "the same (significant or not at α = {}, the same mode); the paper gives no F values, and Table 1 is compared "
        "as counts (these subjects are not the paper's people).",
        paper.count(Agreement::kAgrees), paper.count(Agreement::kDiffers), paper.count(Agreement::kNotMeasured),
        paper.alpha));
    if (!paper.protocol_differences.empty()) {
      doc.paragraph("This study's protocol differs from the paper's: " +
                    fmt::format("{}", fmt::join(paper.protocol_differences, "; ")) + ".");
    }
    Table t{{"point", "source", "the paper", "this study", ""}, {}};
    for (const auto& r : paper.rows) t.rows.push_back({r.point, r.source, r.paper, r.hattr, std::string(agreementName(r.agreement))});
    doc.table(t);
  }
}

/// Table 1: each subject's best mode on both metrics.
void writeBestModeTable(const StudyAnalysis& a, Document& doc) {
  doc.heading("Table 1: each subject's best mode");
  Table table1{{"subject", "best mode, trajectory", "best mode, force profile"}, {}};
  for (const auto& [subject, mode] : a.trajectory.best_mode) table1.rows.push_back({subject, mode, a.force.best_mode.at(subject)});
  doc.table(table1);
}

/// A metric's ANOVA tables: mode × subject (with Tukey's intervals between the modes), then
/// trial × subject per mode, modes in the study's order.
void writeMetricTables(const StudyAnalysis& a, const MetricResult& m, const std::string& title, Document& doc) {
  const std::vector<std::string>& order = a.modes;
  doc.heading(fmt::format("{}: mode × subject ANOVA (subject random)", title));
  doc.table(anovaTable(m.overall));
  if (m.tukey) {
    Table t{{"comparison", "difference", "95 % lower", "95 % upper", "p adjusted"}, {}};
    for (const auto& c : m.tukey->comparisons) t.rows.push_back({c.comparison, g(c.diff), g(c.lower), g(c.upper), p(c.p_adjusted)});
    doc.paragraph(fmt::format("Tukey HSD between modes (error term {}):", m.tukey->error_term));
    doc.table(t);
  }
  doc.heading(fmt::format("{}: per mode, trial × subject ANOVA (effect of training, difference between subjects)", title), 3);
  for (const std::string& mode : order) {
    if (const auto table = m.per_mode.find(mode); table != m.per_mode.end()) {
      doc.paragraph(mode + ":");
      doc.table(anovaTable(table->second));
    }
  }
}

/// Figure: mean cost per recall trial, per mode, with the 95 % confidence interval over
/// subjects at each trial.
void writeMeanByTrialFigure(const StudyAnalysis& a, const MetricResult& m, const std::string& title, Document& doc,
                            std::map<std::string, std::string>& files) {
  const std::vector<std::string>& order = a.modes;
  SvgPlot means(fmt::format("{}: mean recall cost per trial", title), "recall trial", metricUnit(m.metric), 600);
  means.integerX();
  for (const std::string& mode : order) {
    std::map<int, std::vector<double>> by_trial;
    for (const TrialCost& c : a.costs) {
      if (c.mode == mode) by_trial[c.trial].push_back(costOf(c, m.metric));
    }
    Series s{mode, modeColour(mode), {}, 2.0, false, true};
    for (const auto& [trial, values] : by_trial) {
      const auto [mean, ci] = meanWithCi(values);
      s.points.emplace_back(static_cast<double>(trial), mean);
      s.errors.push_back(ci);
    }
    if (!s.points.empty()) means.add(s);
  }
  doc.figure(m.metric + "_mean_by_trial", means.svg(),
             fmt::format("Mean {} cost over subjects for each recall trial, per mode, with 95 % confidence intervals "
                         "over subjects (the paper's figures 5 and 6). The axis starts where the data do, not at zero.",
                         m.metric),
             files);
}

/// A metric's figures per mode: the mean per mode, the mode × subject interaction and the
/// inter-subject variance, modes in the study's order.
void writeModeFigures(const StudyAnalysis& a, const MetricResult& m, const std::string& title, Document& doc,
                      std::map<std::string, std::string>& files) {
  const std::vector<std::string>& order = a.modes;
  // Figure: mean per mode with the 95 % confidence interval of the subjects' means (subjects
  // are the random factor, so they are the unit of replication), and the inter-subject variance.
  std::vector<detail::Bar> mean_bars, var_bars;
  for (const std::string& mode : order) {
    std::vector<double> subject_means;
    for (const auto& [subject, mean] : subjectMeans(a.costs, mode, m.metric)) subject_means.push_back(mean);
    if (subject_means.empty()) continue;
    const auto [mean, ci] = meanWithCi(subject_means);
    mean_bars.push_back({mode, modeColour(mode), mean, ci});
  }
  // Figure: the mode × subject interaction, each subject's mean per mode (x: the modes in
  // order), over the modes' means.
  std::string legend;
  for (std::size_t k = 0; k < order.size(); ++k) legend += fmt::format("{}{} = {}", k == 0 ? "" : ", ", k + 1, order[k]);
  SvgPlot interaction(fmt::format("{}: each subject's mean per mode", title), fmt::format("mode ({})", legend),
                      metricUnit(m.metric), 600);
  interaction.integerX();
  std::map<std::string, Series> by_subject_line;
  Series mode_means{"mean of the subjects", "#000000", {}, 3.0, false, true};
  for (std::size_t k = 0; k < order.size(); ++k) {
    std::vector<double> subject_means;
    for (const auto& [subject, mean] : subjectMeans(a.costs, order[k], m.metric)) {
      subject_means.push_back(mean);
      auto& line = by_subject_line.try_emplace(subject, Series{"a subject", "#9a9a9a", {}, 1.0, false, true}).first->second;
      line.points.emplace_back(static_cast<double>(k + 1), mean);
    }
    if (!subject_means.empty()) mode_means.points.emplace_back(static_cast<double>(k + 1), meanWithCi(subject_means).first);
  }
  for (auto& [subject, line] : by_subject_line) interaction.add(std::move(line));
  interaction.add(mode_means);
  for (const auto& v : m.inter_subject) var_bars.push_back({v.level, modeColour(v.level), v.variance});
  std::sort(var_bars.begin(), var_bars.end(),
            [&order](const auto& x, const auto& y) { return modeRank(order, x.label) < modeRank(order, y.label); });
  SvgPlot mean_plot(fmt::format("{}: mean recall cost per mode", title), "mode", metricUnit(m.metric), 420, 300);
  mean_plot.bars(mean_bars);
  doc.figure(m.metric + "_mean_per_mode", mean_plot.svg(),
             fmt::format("Mean {} cost per mode over all recall trials, with the 95 % confidence interval of the "
                         "subjects' means (Student's t, subjects − 1 degrees of freedom).",
                         m.metric),
             files);
  doc.figure(m.metric + "_mode_by_subject", interaction.svg(),
             fmt::format("The mode × subject interaction on the {} metric: each subject's mean recall cost in each "
                         "mode (grey), and the mean over subjects (black). Lines that cross are the interaction.",
                         m.metric),
             files);
  SvgPlot var_plot(fmt::format("{}: inter-subject variance per mode", title), "mode", "variance of subject means", 420, 300);
  var_plot.bars(var_bars);
  doc.figure(m.metric + "_variance_per_mode", var_plot.svg(),
             fmt::format("Variance over subjects of each subject's mean {} cost, per mode.", m.metric), files);
}

/// Each subject's last recall trial in each mode: "subject/mode" -> its last recall trial.
std::map<std::string, const TrialCost*> lastRecallTrials(const StudyAnalysis& a) {
  std::map<std::string, const TrialCost*> last_recall;  // "subject/mode" -> its last recall trial
  for (const auto& c : a.costs) {
    auto& slot = last_recall[c.subject + "/" + c.mode];
    if (!slot || c.trial > slot->trial) slot = &c;
  }
  return last_recall;
}

/// Figure 3: the expert's force on each axis over time, and one subject's last recall trial in
/// each mode (modes in `order`).
void writeProfileFigures(const session::StudyDatabase& db, const std::vector<std::string>& order,
                         const HapticProfile& expert, const std::map<std::string, const TrialCost*>& last_recall,
                         const std::string& first_subject, Document& doc, std::map<std::string, std::string>& files) {
  const char* axes[] = {"fx", "fy", "fz"};
  for (int k = 0; k < 3; ++k) {
    SvgPlot plot(fmt::format("Force {} over time: expert and {}'s last recall trials", axes[k], first_subject), "time [s]",
                 fmt::format("{} [N] (force on the paper)", axes[k]), 640);
    Series e{"expert", "#000000", {}, 2.0};
    for (const Sample& s : expert.samples()) e.points.emplace_back(s.t_s, channelValue(s, *channelFromName(axes[k])));
    plot.add(e);
    for (const std::string& mode : order) {
      const auto found = last_recall.find(first_subject + "/" + mode);
      if (found == last_recall.end()) continue;
      const TrialCost* cost = found->second;
      const HapticProfile trial = db.trialProfile(cost->trial_id);
      Series s{cost->mode, modeColour(cost->mode), {}, 1.2};
      for (const Sample& x : trial.samples()) s.points.emplace_back(x.t_s, channelValue(x, *channelFromName(axes[k])));
      plot.add(s);
    }
    doc.figure(fmt::format("profile_{}", axes[k]), plot.svg(),
               fmt::format("The expert's {} and one subject's last recall trial in each mode (the paper's figure 3).", axes[k]),
               files);
  }
}

/// The paper's figure 3: one subject's haptic profile on two occasions (there a week apart;
/// here the subject's first and last analyzed recall trial of the first mode), and the expert's.
void writeTwoOccasionsFigure(const session::StudyDatabase& db, const StudyAnalysis& a, const HapticProfile& expert,
                             const std::string& first_subject, Document& doc, std::map<std::string, std::string>& files) {
  const std::vector<std::string>& order = a.modes;
  const TrialCost* first_occasion = nullptr;
  const TrialCost* last_occasion = nullptr;
  for (const TrialCost& c : a.costs) {
    if (c.subject != first_subject || order.empty() || c.mode != order.front()) continue;
    if (!first_occasion || c.trial < first_occasion->trial) first_occasion = &c;
    if (!last_occasion || c.trial > last_occasion->trial) last_occasion = &c;
  }
  if (first_occasion && last_occasion && first_occasion != last_occasion) {
    SvgPlot plot(fmt::format("Force fz of {} on two occasions ({} recall trials {} and {}) and the expert's", first_subject,
                             order.front(), first_occasion->trial, last_occasion->trial),
                 "time [s]", "fz [N] (force on the paper)", 640);
    Series e{"expert", "#000000", {}, 2.0};
    for (const Sample& s : expert.samples()) e.points.emplace_back(s.t_s, s.f_user_W.z());
    plot.add(e);
    for (const auto& [occasion, colour, dashed] : {std::tuple{first_occasion, "#ff7f0e", true}, std::tuple{last_occasion, "#1f77b4", false}}) {
      Series s{fmt::format("recall trial {}", occasion->trial), colour, {}, 1.2, dashed};
      const HapticProfile trial = db.trialProfile(occasion->trial_id);
      for (const Sample& x : trial.samples()) s.points.emplace_back(x.t_s, x.f_user_W.z());
      plot.add(s);
    }
    doc.figure("profile_two_occasions", plot.svg(),
               fmt::format("One subject's haptic profile (fz) on two occasions, the first and last analyzed recall trials "
                           "after {} training, with the expert's (the paper's figure 3: the same subject a week apart).",
                           order.front()),
               files);
  }
}

/// The pen-down path in mm, broken (a NaN point) where the pen lifts.
std::vector<std::pair<double, double>> penDownPath_mm(const HapticProfile& profile) {
  std::vector<std::pair<double, double>> points;
  bool was_down = false;
  for (const Sample& s : profile.samples()) {
    if (s.pen_down) {
      points.emplace_back(units::metresToMillimetres(s.p_WT.x()), units::metresToMillimetres(s.p_WT.y()));
    } else if (was_down) {
      points.emplace_back(std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN());
    }
    was_down = s.pen_down;
  }
  return points;
}

/// Per mode of the study: every subject's last recall trajectory (pen down) over the expert's.
void writeTrajectoryFigures(const session::StudyDatabase& db, const HapticProfile& expert,
                            const std::map<std::string, const TrialCost*>& last_recall, Document& doc,
                            std::map<std::string, std::string>& files) {
  for (const auto mode : db.study().modes) {
    const std::string name(guidance::modeName(mode));
    SvgPlot plot(fmt::format("Recall trajectories after {} training", name), "x [mm]", "y [mm]", 560, 420);
    plot.equalAspect();
    Series e{"expert", "#000000", penDownPath_mm(expert), 2.5};
    for (const auto& [key, cost] : last_recall) {
      if (cost->mode != name) continue;
      const HapticProfile trial = db.trialProfile(cost->trial_id);
      plot.add(Series{name + " subjects", modeColour(name), penDownPath_mm(trial), 1.0});
    }
    plot.add(e);
    doc.figure(fmt::format("trajectories_{}", name), plot.svg(),
               fmt::format("Every subject's last recall trajectory after {} training (pen down), over the expert's.", name), files);
  }
}

}  // namespace

std::filesystem::path writeStudyReport(const session::StudyDatabase& db, const StudyAnalysis& a,
                                       const std::filesystem::path& out) {
  const session::StudyDefinition& study = db.study();
  std::map<std::string, std::string> files;
  Document doc;
  doc.heading(fmt::format("Study report: {}", study.name), 1);
  const auto subjects = db.subjects();
  doc.heading("Summary");
  doc.list(paperSummary(study, a, subjects.size(), chooseAnalysis(db).reason));

  // Design.
  writeDesignSection(study, subjects, a, doc);

  // Conclusions first, then the numbers behind them.
  doc.heading("Conclusions");
  doc.list(conclusions(a));

  // The paper's findings beside this study's.
  writePaperComparison(study, subjects.size(), a, doc);

  // Table 1.
  writeBestModeTable(a, doc);

  // Per metric: ANOVA tables and figures 5/6, modes in the study's order.
  for (const MetricResult* m : {&a.trajectory, &a.force}) {
    const std::string title = m->metric == "trajectory" ? "Trajectory" : "Haptic profile (force)";
    writeMetricTables(a, *m, title, doc);
    writeMeanByTrialFigure(a, *m, title, doc, files);
    writeModeFigures(a, *m, title, doc, files);
  }

  // Figure 3: haptic profiles over time; and trajectories over the expert's.
  const HapticProfile expert = db.expert(study.skill);
  const std::map<std::string, const TrialCost*> last_recall = lastRecallTrials(a);
  const std::string first_subject = subjects.empty() ? "" : subjects.front().id;
  doc.heading("Haptic profiles and trajectories");
  writeProfileFigures(db, a.modes, expert, last_recall, first_subject, doc, files);
  writeTwoOccasionsFigure(db, a, expert, first_subject, doc, files);
  writeTrajectoryFigures(db, expert, last_recall, doc, files);

  // Write the files.
  writeReportFiles(out, study.name, doc, files);
  return out / "report.html";
}

}  // namespace hattr::report
