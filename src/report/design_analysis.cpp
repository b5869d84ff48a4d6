// The design analysis: every completed trial scored against its skill's expert, then tabulated
// (learning curves, session and phase cells, retention, transfer, one learner's scores). The
// models and curve fits are in design_models.cpp, JSON and CSV in design_tables.cpp, the
// summary and conclusions in words in design_summary.cpp.

#include "hattr/report/design_analysis.hpp"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <map>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "hattr/analysis/kinematics.hpp"
#include "hattr/core/error.hpp"
#include "hattr/session/subject_trials.hpp"
#include "design_analysis_internal.hpp"
#include "report_document.hpp"

namespace hattr::report {
namespace {

using session::StrategyRef;

/// Conditions: the groups when there are several; else, when the one group compares
/// strategies, each block's strategy ("none" for a block that names none); else the group.
std::string conditionKind(const session::StudyDefinition& study) {
  return study.groups.size() == 1 && study.groups.front().strategies.size() > 1 ? "strategy" : "group";
}

std::string strategyOf(const session::StudyDefinition& study, const session::TrialPlan& plan) {
  const bool named = session::blockOf(study, plan).strategy.kind != StrategyRef::Kind::kNone;
  return named ? std::string(guidance::modeName(plan.mode)) : "none";
}

std::vector<std::string> conditionsOf(const session::StudyDefinition& study, const std::string& kind) {
  std::vector<std::string> out;
  if (kind == "group") {
    for (const auto& g : study.groups) out.push_back(g.name);
    return out;
  }
  for (const auto m : study.groups.front().strategies) out.emplace_back(guidance::modeName(m));
  out.emplace_back("none");
  return out;
}

/// Each subject's mean of `values` (subject -> values), then the mean over subjects.
SubjectMean overSubjects(const std::map<std::string, std::vector<double>>& values) {
  std::vector<double> means;
  for (const auto& [subject, v] : values) {
    if (!v.empty()) means.push_back(detail::meanWithCi(v).first);
  }
  return meanOverSubjects(means);
}

/// Per subject: shape and force values of the scores that `select` takes.
template <class Select>
std::pair<SubjectMean, SubjectMean> shapeAndForce(const std::vector<DesignTrialScore>& scores, Select select) {
  std::map<std::string, std::vector<double>> shape, force;
  for (const DesignTrialScore& s : scores) {
    if (!select(s)) continue;
    shape[s.subject].push_back(s.shape());
    force[s.subject].push_back(s.force());
  }
  return {overSubjects(shape), overSubjects(force)};
}

/// Every completed trial with its place, and why the analysis leaves it out ("" when it takes
/// it); counts what is left out.
std::vector<DesignTrialScore> completedTrials(const session::StudyDatabase& db,
                                             const std::vector<session::TrialRecord>& records, DesignAnalysis& out) {
  const session::StudyDefinition& study = db.study();
  const bool exclude = study.protocol.disturbed == session::DisturbedPolicy::kExclude;
  // A paper's design: its recall trials as the paper's analysis takes them (spares included).
  const bool paper = session::isPaperDesign(study);
  const std::map<std::int64_t, int> paper_recall = paper ? paperRecallTrials(db, records) : std::map<std::int64_t, int>{};
  std::vector<DesignTrialScore> scores;
  std::map<std::tuple<std::string, std::string, std::string, std::string>, int> in_phase;
  for (const session::TrialRecord& t : records) {
    ++out.trials_planned;
    if (t.status != session::TrialStatus::kCompleted) {
      ++out.trials_pending;
      continue;
    }
    DesignTrialScore s;
    if (!t.disturbed.empty() && exclude) {
      ++out.trials_excluded;
      s.left_out = "disturbed (policy \"exclude\")";
    } else if (paper && t.plan.phase == session::kPhaseRecall && !paper_recall.contains(t.id)) {
      s.left_out = "not an analyzed recall trial (protocol.analyzed_recall_trials)";
    } else {
      out.trials_flagged += t.disturbed.empty() ? 0 : 1;
    }
    s.trial_id = t.id;
    s.subject = t.plan.subject;
    s.group = t.plan.group;
    s.strategy = strategyOf(study, t.plan);
    s.condition = out.condition_kind == "group" ? s.group : s.strategy;
    s.session = t.plan.session + 1;
    s.day = t.plan.day;
    s.block = t.plan.block + 1;
    s.phase = t.plan.phase;
    s.skill = t.plan.skill;
    s.trial = t.plan.index;
    s.trial_in_phase = ++in_phase[{s.subject, s.phase, s.condition, s.skill}];
    // A spare takes the number of the recall trial it stands in for, as in the paper's analysis.
    if (const auto place = paper_recall.find(t.id); place != paper_recall.end()) s.trial_in_phase = place->second;
    s.guided = t.plan.view.guidance;
    s.disturbed = t.disturbed;
    scores.push_back(std::move(s));
  }
  return scores;
}

/// A trial's kinematics as stored with it (SubjectTrials::measure), else measured now.
std::map<std::string, double> kinematicsOf(const HapticProfile& profile) {
  constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();
  std::map<std::string, double> out;
  const auto& extra = profile.metadata().extra;
  for (const char* name : analysis::kinematicsNames()) {
    const auto it = extra.find(session::kKinematicsPrefix + std::string(name));
    if (it == extra.end()) {
      out.clear();
      break;
    }
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    out[name] = it->second == "NA" || end == it->second.c_str() ? kMissing : v;
  }
  if (!out.empty()) return out;
  const nlohmann::json k = analysis::toJson(analysis::trialKinematics(profile));
  for (const char* name : analysis::kinematicsNames()) out[name] = k.at(name).is_null() ? kMissing : k.at(name).get<double>();
  return out;
}

/// Scores every analyzed trial against its skill's expert, a chunk at a time.
void scoreTrials(const session::StudyDatabase& db, const AnalysisOptions& options, std::vector<DesignTrialScore>& scores) {
  std::map<std::string, analysis::TrialScorer> scorers;
  for (const auto& [skill, file] : db.study().experts) {
    scorers.emplace(skill, analysis::TrialScorer(db.expert(skill), {.normalization = options.normalization,
                                                                     .cost = options.cost,
                                                                     .band_fraction = options.band_fraction}));
  }
  const std::size_t chunk = std::max<std::size_t>(32, analysis::dtwBatchWidth());
  const int total = static_cast<int>(scores.size());
  if (options.progress) options.progress(0, total);
  for (std::size_t first = 0; first < scores.size(); first += chunk) {
    const std::size_t last = std::min(scores.size(), first + chunk);
    // The chunk's trials not scored already, by skill: each scorer takes its own at once.
    std::map<std::string, std::vector<std::size_t>> by_skill;
    for (std::size_t i = first; i < last; ++i) {
      if (const auto* known = options.scoredAlready(scores[i].trial_id)) {
        scores[i].score = *known;
        if (options.kinematics_of_scored) scores[i].kinematics = kinematicsOf(db.trialProfile(scores[i].trial_id));
      } else {
        by_skill[scores[i].skill].push_back(i);
      }
    }
    for (const auto& [skill, indices] : by_skill) {
      std::vector<HapticProfile> profiles;
      for (const std::size_t i : indices) profiles.push_back(db.trialProfile(scores[i].trial_id));
      std::vector<const HapticProfile*> pointers;
      for (const auto& p : profiles) pointers.push_back(&p);
      const auto result = scorers.at(skill).scoreAll(pointers, options.threads);
      for (std::size_t k = 0; k < indices.size(); ++k) {
        scores[indices[k]].score = result[k];
        scores[indices[k]].kinematics = kinematicsOf(profiles[k]);
      }
    }
    if (options.progress) options.progress(static_cast<int>(last), total);
  }
}

void tabulateCurvesAndCells(DesignAnalysis& a) {
  std::set<std::tuple<std::string, std::string, int>> points;
  std::set<std::tuple<std::string, int, std::string, std::string>> cells;
  for (const DesignTrialScore& s : a.scores) {
    points.insert({s.condition, s.phase, s.trial_in_phase});
    cells.insert({s.condition, s.session, s.phase, s.skill});
    if (std::find(a.phases.begin(), a.phases.end(), s.phase) == a.phases.end()) a.phases.push_back(s.phase);
  }
  for (const auto& [condition, phase, trial] : points) {
    const auto [shape, force] = shapeAndForce(a.scores, [&](const DesignTrialScore& s) {
      return s.condition == condition && s.phase == phase && s.trial_in_phase == trial;
    });
    a.curves.push_back({condition, phase, trial, shape, force});
  }
  for (const auto& [condition, session, phase, skill] : cells) {
    const auto [shape, force] = shapeAndForce(a.scores, [&](const DesignTrialScore& s) {
      return s.condition == condition && s.session == session && s.phase == phase && s.skill == skill;
    });
    a.cells.push_back({condition, session, phase, skill, shape, force});
  }
  // Cells in the study's order: session, then where the phase first comes, then condition.
  const auto rank = [&a](const std::string& phase) { return std::find(a.phases.begin(), a.phases.end(), phase) - a.phases.begin(); };
  const auto condition_rank = [&a](const std::string& c) {
    return std::find(a.conditions.begin(), a.conditions.end(), c) - a.conditions.begin();
  };
  std::stable_sort(a.cells.begin(), a.cells.end(), [&](const PhaseCell& x, const PhaseCell& y) {
    return std::tuple(x.session, rank(x.phase), condition_rank(x.condition)) <
           std::tuple(y.session, rank(y.phase), condition_rank(y.condition));
  });
}

/// Retention against the last post-test before it (else the last training block), per subject.
void tabulateRetention(DesignAnalysis& a) {
  std::set<std::pair<std::string, std::string>> conditions_and_skills;
  for (const DesignTrialScore& s : a.scores) {
    if (s.phase == session::kPhaseRetention) conditions_and_skills.insert({s.condition, s.skill});
  }
  for (const auto& [condition, skill] : conditions_and_skills) {
    RetentionRow row{condition, skill, std::string(session::kPhasePostTest), {}, {}, {}, {}, {}, {}};
    std::map<std::string, std::vector<double>> before_shape, before_force, after_shape, after_force, change_shape,
        change_force;
    // The subjects of this condition, each on its own.
    std::set<std::string> subjects;
    for (const DesignTrialScore& s : a.scores) {
      if (s.condition == condition && s.skill == skill && s.phase == session::kPhaseRetention) subjects.insert(s.subject);
    }
    bool any_post_test = false;
    for (const std::string& subject : subjects) {
      std::vector<const DesignTrialScore*> mine;
      for (const DesignTrialScore& s : a.scores) {
        if (s.subject == subject && s.skill == skill) mine.push_back(&s);
      }
      const auto first_retention = std::find_if(mine.begin(), mine.end(), [](const auto* s) {
        return s->phase == session::kPhaseRetention;
      });
      // The block before retention to compare with: the last post-test, else the last training.
      std::pair<int, int> chosen{-1, -1};  // session, block
      for (const char* phase : {session::kPhasePostTest.data(), session::kPhaseTraining.data()}) {
        for (auto it = mine.begin(); it != first_retention; ++it) {
          if ((*it)->phase == phase) chosen = {(*it)->session, (*it)->block};
        }
        if (chosen.first >= 0) {
          any_post_test = any_post_test || phase == session::kPhasePostTest;
          break;
        }
      }
      if (chosen.first < 0) continue;
      std::vector<double> bs, bf, rs, rf;
      for (const auto* s : mine) {
        if (s->session == chosen.first && s->block == chosen.second) {
          bs.push_back(s->shape());
          bf.push_back(s->force());
        } else if (s->phase == session::kPhaseRetention) {
          rs.push_back(s->shape());
          rf.push_back(s->force());
        }
      }
      if (bs.empty() || rs.empty()) continue;
      const double b_shape = detail::meanWithCi(bs).first, b_force = detail::meanWithCi(bf).first;
      const double r_shape = detail::meanWithCi(rs).first, r_force = detail::meanWithCi(rf).first;
      // Each subject's own scores: the block compared with (its phase), retention, the change.
      const std::string compared = [&] {
        for (const auto* x : mine) {
          if (x->session == chosen.first && x->block == chosen.second) return x->phase;
        }
        return std::string();
      }();
      a.subject_scores.push_back({subject, condition, skill, compared, b_shape, b_force});
      a.subject_scores.push_back({subject, condition, skill, std::string(session::kPhaseRetention), r_shape, r_force});
      a.subject_scores.push_back({subject, condition, skill, "retention-change", r_shape - b_shape, r_force - b_force});
      before_shape[subject] = {b_shape};
      before_force[subject] = {b_force};
      after_shape[subject] = {r_shape};
      after_force[subject] = {r_force};
      change_shape[subject] = {r_shape - b_shape};
      change_force[subject] = {r_force - b_force};
    }
    if (!any_post_test) row.before = session::kPhaseTraining;
    row.shape_before = overSubjects(before_shape);
    row.shape_retention = overSubjects(after_shape);
    row.shape_change = overSubjects(change_shape);
    row.force_before = overSubjects(before_force);
    row.force_retention = overSubjects(after_force);
    row.force_change = overSubjects(change_force);
    a.retention.push_back(row);
  }
}

void tabulateTransfer(DesignAnalysis& a) {
  std::set<std::pair<std::string, std::string>> conditions_and_skills;
  for (const DesignTrialScore& s : a.scores) {
    if (s.phase == session::kPhaseTransfer) conditions_and_skills.insert({s.condition, s.skill});
  }
  for (const auto& [condition, skill] : conditions_and_skills) {
    const auto [shape, force] = shapeAndForce(a.scores, [&](const DesignTrialScore& s) {
      return s.condition == condition && s.skill == skill && s.phase == session::kPhaseTransfer;
    });
    a.transfer.push_back({condition, skill, shape, force});
    // Each subject's own transfer mean.
    std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> by_subject;
    for (const DesignTrialScore& s : a.scores) {
      if (s.condition != condition || s.skill != skill || s.phase != session::kPhaseTransfer) continue;
      by_subject[s.subject].first.push_back(s.shape());
      by_subject[s.subject].second.push_back(s.force());
    }
    for (const auto& [subject, values] : by_subject) {
      a.subject_scores.push_back({subject, condition, skill, std::string(session::kPhaseTransfer),
                                  detail::meanWithCi(values.first).first, detail::meanWithCi(values.second).first});
    }
  }
}

/// One learner: per condition, phase and skill, the first, best and latest shape cost.
void tabulateLearner(DesignAnalysis& a) {
  if (a.subjects != 1) return;
  std::vector<std::tuple<std::string, std::string, std::string>> keys;
  for (const DesignTrialScore& s : a.scores) {
    const auto key = std::tuple(s.condition, s.phase, s.skill);
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  }
  for (const auto& [condition, phase, skill] : keys) {
    LearnerRow row{condition, phase, skill, 0, 0.0, std::numeric_limits<double>::infinity(), 0, 0.0, 0.0};
    double sum = 0.0;
    for (const DesignTrialScore& s : a.scores) {
      if (s.condition != condition || s.phase != phase || s.skill != skill) continue;
      if (row.trials++ == 0) row.first = s.shape();
      if (s.shape() < row.best) {
        row.best = s.shape();
        row.best_trial = s.trial_in_phase;
      }
      row.latest = s.shape();
      sum += s.shape();
    }
    row.mean = sum / row.trials;
    a.learner.push_back(row);
  }
}

}  // namespace

SubjectMean meanOverSubjects(const std::vector<double>& values) {
  if (values.empty()) return {0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  const auto [mean, ci] = detail::meanWithCi(values);
  return {static_cast<int>(values.size()), mean, ci};
}

analysis::OneWayData groupSubjectMeans(const std::vector<const DesignTrialScore*>& scores, bool shape) {
  std::vector<std::string> subject, group;
  std::vector<double> value;
  for (const auto* s : scores) {
    subject.push_back(s->subject);
    group.push_back(s->group);
    value.push_back(shape ? s->shape() : s->force());
  }
  return groupSubjectMeans(subject, group, value);
}

analysis::OneWayData groupSubjectMeans(const std::vector<std::string>& subject, const std::vector<std::string>& group,
                                       const std::vector<double>& value) {
  std::map<std::string, std::pair<std::string, std::vector<double>>> by_subject;
  for (std::size_t k = 0; k < subject.size(); ++k) {
    auto& [its_group, values] = by_subject[subject[k]];
    its_group = group[k];
    values.push_back(value[k]);
  }
  analysis::OneWayData data;
  for (const auto& [id, entry] : by_subject) {
    double sum = 0.0;
    for (const double v : entry.second) sum += v;
    data.group.push_back(entry.first);
    data.y.push_back(sum / static_cast<double>(entry.second.size()));
  }
  return data;
}

DesignAnalysis analyzeDesign(const session::StudyDatabase& db, const AnalysisOptions& options) {
  const session::StudyDefinition& study = db.study();
  DesignAnalysis a;
  a.options = options;
  a.options.progress = nullptr;  // the caller's callback does not outlive the call
  a.condition_kind = conditionKind(study);
  a.conditions = conditionsOf(study, a.condition_kind);
  a.disturbed_policy = std::string(session::disturbedPolicyName(study.protocol.disturbed));
  // The trial records, read once: every count, selection and the choice of analysis below judge
  // the same snapshot of a study that other stations may be adding to.
  const std::vector<session::TrialRecord> records = db.trials();
  std::vector<DesignTrialScore> completed = completedTrials(db, records, a);
  HATTR_THROW_UNLESS(!completed.empty(), "{}: no trial of the study is completed yet ({} planned); run the study first",
                     db.file().string(), a.trials_planned);
  scoreTrials(db, options, completed);
  for (DesignTrialScore& s : completed) (s.left_out.empty() ? a.scores : a.left_out).push_back(std::move(s));
  HATTR_THROW_UNLESS(!a.scores.empty(), "{}: none of the {} completed trials is analyzed ({}, ...)", db.file().string(),
                     a.left_out.size(), a.left_out.front().left_out);
  std::set<std::string> subjects;
  for (const DesignTrialScore& s : a.scores) subjects.insert(s.subject);
  a.subjects = static_cast<int>(subjects.size());
  a.paper_design = session::isPaperDesign(study);
  a.reason = chooseAnalysis(db, records).reason;
  if (a.subjects == 1 && a.reason.rfind("one learner", 0) != 0) {  // the others' trials all excluded
    a.reason = "one learner (1 subject with analyzed trials): there are no between-subject statistics";
  }
  tabulateCurvesAndCells(a);
  tabulateRetention(a);
  tabulateTransfer(a);
  detail::fitPhaseModels(a);
  detail::fitCurves(a);
  tabulateLearner(a);
  // Rows in the study's order of conditions.
  const auto rank = [&a](const std::string& c) { return std::find(a.conditions.begin(), a.conditions.end(), c) - a.conditions.begin(); };
  std::stable_sort(a.retention.begin(), a.retention.end(),
                   [&](const RetentionRow& x, const RetentionRow& y) { return rank(x.condition) < rank(y.condition); });
  std::stable_sort(a.transfer.begin(), a.transfer.end(),
                   [&](const TransferRow& x, const TransferRow& y) { return rank(x.condition) < rank(y.condition); });
  return a;
}

}  // namespace hattr::report
