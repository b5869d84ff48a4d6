// The design analysis in words: the report's opening summary and its conclusions, each stating
// only what the numbers show.

#include "hattr/report/design_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

namespace hattr::report {

std::vector<std::string> designConclusions(const DesignAnalysis& a) {
  std::vector<std::string> out;
  if (a.trials_pending > 0) {
    out.push_back(fmt::format("The study is not finished: {} of {} trials are completed; what follows is what they show.",
                              a.trials_planned - a.trials_pending, a.trials_planned));
  }
  const auto interval = [](const SubjectMean& m) {
    return std::isfinite(m.ci) ? fmt::format("{:.4g} (95 % CI {:.4g} to {:.4g}, {} subjects)", m.mean, m.mean - m.ci,
                                             m.mean + m.ci, m.subjects)
                               : fmt::format("{:.4g} ({} subject{})", m.mean, m.subjects, m.subjects == 1 ? "" : "s");
  };
  // Retention: did the cost rise from the last test before it? Only an interval that excludes 0 says so.
  for (const RetentionRow& r : a.retention) {
    const SubjectMean& c = r.shape_change;
    const bool known = std::isfinite(c.ci);
    const std::string verdict = !known ? "too few subjects to tell"
                                : c.mean - c.ci > 0.0 ? "the shape cost rose: part of what was learned was lost"
                                : c.mean + c.ci < 0.0 ? "the shape cost fell further"
                                                      : "no change the interval can tell from none";
    out.push_back(fmt::format("Retention of {} ({}): retention − {} shape cost {}: {}.", r.condition, r.skill, r.before,
                              interval(c), verdict));
  }
  for (const TransferRow& t : a.transfer) {
    out.push_back(fmt::format("Transfer of {} to {}: mean shape cost {}.", t.condition, t.skill, interval(t.shape)));
  }
  if (a.trials_excluded > 0 || a.trials_flagged > 0) {
    out.push_back(fmt::format("Disturbed trials (policy \"{}\"): {} left out, {} analyzed and flagged.", a.disturbed_policy,
                              a.trials_excluded, a.trials_flagged));
  }
  return out;
}

namespace {

std::string pText(double p) { return !std::isfinite(p) ? "p not known" : p < 0.001 ? "p < 0.001" : fmt::format("p = {:.3f}", p); }

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i == 0 ? "" : i + 1 == items.size() ? " and " : ", ") + items[i];
  return out;
}

/// A phase's shape model in words: the test, then each condition against the reference.
std::string modelSentence(const DesignAnalysis& a, const PhaseModel& m) {
  const auto term = std::find_if(m.fit.terms.begin(), m.fit.terms.end(),
                                 [&](const analysis::LmmTermTest& t) { return t.term == a.condition_kind; });
  if (term == m.fit.terms.end()) return "";
  const std::string test = fmt::format("F({:g}, {:.1f}) = {:.2f}, {}", term->num_df, term->den_df, term->f, pText(term->p));
  std::vector<std::string> differences;
  for (const analysis::LmmCoefficient& c : m.fit.fixed) {
    if (c.name.rfind(a.condition_kind, 0) != 0) continue;
    differences.push_back(fmt::format("{} {:+.3g} (95 % CI {:.3g} to {:.3g})", c.name.substr(a.condition_kind.size()),
                                      c.estimate, c.lower, c.upper));
  }
  const bool differed = term->p < 0.05;
  std::string text =
      differed ? fmt::format("In {}, the shape cost differed between the {}s ({}).", m.phase, a.condition_kind, test)
               : fmt::format("In {}, no {} had a shape cost the test can tell from the others' ({}).", m.phase,
                             a.condition_kind, test);
  text += fmt::format(" Compared with {} (lower is closer to the expert): {}.", m.reference, joined(differences));
  if (m.fit.singular) text += " The fit is singular (a variance estimated as zero): read it with care.";
  return text;
}

/// The trend of a condition's mean cost over a phase: the least-squares slope over its trials
/// with its 95 % interval (whatever the curve's shape), and the exponential law's level where
/// its fit is sound. Rising costs on unguided trials are forgetting or fatigue, not learning.
std::string trendSentence(const DesignAnalysis& a, const std::string& condition, const std::string& phase) {
  std::vector<double> n, y;
  for (const CurvePoint& p : a.curves) {
    if (p.condition != condition || p.phase != phase || !std::isfinite(p.shape.mean)) continue;
    n.push_back(p.trial_in_phase);
    y.push_back(p.shape.mean);
  }
  const analysis::LinearTrend trend = analysis::linearTrend(n, y);
  if (!std::isfinite(trend.lower)) return "";
  const bool guided = std::any_of(a.scores.begin(), a.scores.end(), [&](const DesignTrialScore& s) {
    return s.condition == condition && s.phase == phase && s.guided;
  });
  const std::string slope = fmt::format("{:+.3g} per trial, 95 % CI {:.3g} to {:.3g}", trend.slope, trend.lower, trend.upper);
  if (trend.lower <= 0.0 && trend.upper >= 0.0) {
    return fmt::format("Over the {} trials with {}, the shape cost showed no trend the interval can tell from none ({}).",
                       phase, condition, slope);
  }
  std::string text = fmt::format("Over the {} trials with {}{}, the shape cost {} ({}){}", phase, condition,
                                 guided ? " (guidance on)" : "", trend.slope < 0.0 ? "fell" : "rose", slope,
                                 trend.slope < 0.0 ? "" : guided ? ": the guided writing drifted from the expert's"
                                                                 : ": forgetting or fatigue, not learning");
  const auto fit = std::find_if(a.fits.begin(), a.fits.end(), [&](const CurveFitRow& f) {
    return f.subject.empty() && f.metric == "shape" && f.condition == condition && f.phase == phase;
  });
  if (trend.slope < 0.0 && fit != a.fits.end() && fit->exponential.note.empty() && std::isfinite(fit->exponential.asymptote.lower)) {
    text += fmt::format("; the exponential law levels off at {:.3g} (95 % CI {:.3g} to {:.3g})",
                        fit->exponential.asymptote.estimate, fit->exponential.asymptote.lower,
                        fit->exponential.asymptote.upper);
  }
  return text + ".";
}

}  // namespace

std::vector<std::string> designSummary(const DesignAnalysis& a) {
  std::vector<std::string> out;
  std::vector<std::string> present;
  for (const std::string& c : a.conditions) {
    if (std::any_of(a.scores.begin(), a.scores.end(), [&](const DesignTrialScore& s) { return s.condition == c; })) {
      present.push_back(c);
    }
  }
  if (a.subjects == 1) {
    out.push_back(fmt::format("One learner practised ({}: {}), {} trials in {}. These are one person's scores, so no "
                              "strategy is tested against another; the curves, sessions, best and latest scores show the "
                              "learner's progress.",
                              a.condition_kind, joined(present), a.scores.size(), joined(a.phases)));
    for (const LearnerRow& r : a.learner) {
      out.push_back(fmt::format("{} with {} ({}): first shape cost {:.3g}, best {:.3g} (trial {}), latest {:.3g} over {} "
                                "trials.", r.phase, r.condition, r.skill, r.first, r.best, r.best_trial, r.latest, r.trials));
    }
  } else {
    out.push_back(fmt::format("Compared: {} ({}), {} subjects, {} trials in {}. Analysis: {}.",
                              a.condition_kind == "strategy" ? "training strategies, each subject trying each" : "groups",
                              joined(present), a.subjects, a.scores.size(), joined(a.phases), a.reason));
    for (const PhaseModel& m : a.models) {
      if (m.metric != "shape") continue;
      if (!m.skipped.empty()) continue;
      const std::string sentence = modelSentence(a, m);
      if (!sentence.empty()) out.push_back(sentence);
    }
  }
  for (const std::string& condition : present) {
    for (const std::string& phase : a.phases) {
      const std::string sentence = trendSentence(a, condition, phase);
      if (!sentence.empty()) out.push_back(sentence);
    }
  }
  if (a.retention.empty()) {
    out.push_back("What it does not show: whether what was learned lasts, for no retention test was run.");
  }
  if (a.subjects >= 2) {
    out.push_back(fmt::format("A difference the tests cannot tell from none is not evidence that there is none: with {} "
                              "subjects, small effects go unseen.",
                              a.subjects));
  }
  return out;
}

}  // namespace hattr::report
