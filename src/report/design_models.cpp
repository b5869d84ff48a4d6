// The design analysis's models: each phase's conditions compared by a linear mixed model, and
// learning curves fitted by both laws of practice (analyzeDesign runs them on its tables).

#include "design_analysis_internal.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "report_document.hpp"

namespace hattr::report {
namespace {

/// The conditions of a phase's trials, in the study's order.
std::vector<std::string> conditionsIn(const DesignAnalysis& a, const std::string& phase) {
  std::vector<std::string> out;
  for (const std::string& c : a.conditions) {
    const bool present = std::any_of(a.scores.begin(), a.scores.end(),
                                     [&](const DesignTrialScore& s) { return s.phase == phase && s.condition == c; });
    if (present) out.push_back(c);
  }
  return out;
}

/// Both laws of practice fitted to a series of (trial, cost); none when it has fewer than 4
/// trials or does not vary.
bool fitBoth(const std::vector<double>& n, const std::vector<double>& y, CurveFitRow& row) {
  if (n.size() < 4 || *std::max_element(y.begin(), y.end()) == *std::min_element(y.begin(), y.end())) return false;
  try {
    row.exponential = analysis::fitLearningCurve(n, y, analysis::CurveLaw::kExponential);
    row.power = analysis::fitLearningCurve(n, y, analysis::CurveLaw::kPower);
  } catch (const Error&) {
    return false;
  }
  return true;
}

}  // namespace

namespace detail {

/// Each phase's conditions compared by a linear mixed model of its trials: subjects random,
/// and a subject's own condition effect random too where each subject did several conditions
/// with several trials each (the model R's aov(y ~ c + Error(subject/c)) approximates).
void fitPhaseModels(DesignAnalysis& a) {
  if (a.subjects < 2) return;
  const std::string& kind = a.condition_kind;
  for (const std::string& phase : a.phases) {
    const std::vector<std::string> present = conditionsIn(a, phase);
    for (const bool shape : {true, false}) {
      PhaseModel m{phase, shape ? "shape" : "force", present.empty() ? "" : present.front(), {}, ""};
      if (present.size() < 2) {
        m.skipped = fmt::format("one {} only", kind);
        a.models.push_back(std::move(m));
        continue;
      }
      std::vector<std::string> subject, condition;
      std::vector<double> value;
      for (const DesignTrialScore& s : a.scores) {
        if (s.phase != phase) continue;
        subject.push_back(s.subject);
        condition.push_back(s.condition);
        value.push_back(shape ? s.shape() : s.force());
      }
      try {
        m.fit = fitConditionModel(subject, condition, value, kind, m.metric, m.reference, "the " + phase + " trials");
      } catch (const Error& e) {  // data the model cannot take: said, and the rest of the analysis goes on
        m.skipped = e.what();
      }
      a.models.push_back(std::move(m));
    }
  }
}

/// Learning curves fitted per condition and phase (the mean over subjects at each trial), and
/// per subject (their own cost at each trial, averaged over skills at the same trial).
void fitCurves(DesignAnalysis& a) {
  for (const std::string& condition : a.conditions) {
    for (const std::string& phase : a.phases) {
      for (const bool shape : {true, false}) {
        CurveFitRow row{condition, phase, "", shape ? "shape" : "force", {}, {}};
        std::vector<double> n, y;
        for (const CurvePoint& p : a.curves) {
          if (p.condition != condition || p.phase != phase) continue;
          n.push_back(p.trial_in_phase);
          y.push_back(shape ? p.shape.mean : p.force.mean);
        }
        if (fitBoth(n, y, row)) a.fits.push_back(row);
        if (a.subjects < 2) continue;  // one learner: the mean curve is theirs
        // Each subject's own curve.
        std::map<std::string, std::map<int, std::vector<double>>> by_subject;
        for (const DesignTrialScore& s : a.scores) {
          if (s.condition == condition && s.phase == phase) by_subject[s.subject][s.trial_in_phase].push_back(shape ? s.shape() : s.force());
        }
        for (const auto& [subject, trials] : by_subject) {
          CurveFitRow own{condition, phase, subject, row.metric, {}, {}};
          std::vector<double> sn, sy;
          for (const auto& [trial, values] : trials) {
            sn.push_back(trial);
            sy.push_back(detail::meanWithCi(values).first);
          }
          if (fitBoth(sn, sy, own)) a.fits.push_back(own);
        }
      }
    }
  }
}

}  // namespace detail

analysis::LmmFit fitConditionModel(const std::vector<std::string>& subject, const std::vector<std::string>& condition,
                                   const std::vector<double>& value, const std::string& condition_name,
                                   const std::string& response, const std::string& reference,
                                   const std::string& source) {
  analysis::DataTable t{{{"subject", subject, {}}, {condition_name, condition, {}}, {response, {}, value}}, source};
  // Subjects' own condition effects where they did several conditions several times each.
  std::map<std::pair<std::string, std::string>, int> per_cell;
  std::map<std::string, std::set<std::string>> conditions_of;
  for (std::size_t k = 0; k < subject.size(); ++k) {
    ++per_cell[{subject[k], condition[k]}];
    conditions_of[subject[k]].insert(condition[k]);
  }
  const bool within = std::any_of(conditions_of.begin(), conditions_of.end(), [](const auto& e) { return e.second.size() > 1; });
  const bool replicated = std::any_of(per_cell.begin(), per_cell.end(), [](const auto& e) { return e.second > 1; });
  const std::string formula = fmt::format("{} ~ {} + (1 | subject){}", response, condition_name,
                                          within && replicated ? fmt::format(" + (1 | subject:{})", condition_name) : "");
  return analysis::fitLmm(t, formula, {.reference = {{condition_name, reference}}});
}
}  // namespace hattr::report
