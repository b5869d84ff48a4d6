#include "hattr/report/design_analysis.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "hattr/analysis/kinematics.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/table_csv.hpp"
#include "hattr/session/subject_trials.hpp"
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
std::vector<DesignTrialScore> completedTrials(const session::StudyDatabase& db, DesignAnalysis& out) {
  const session::StudyDefinition& study = db.study();
  const bool exclude = study.protocol.disturbed == session::DisturbedPolicy::kExclude;
  // A paper's design: its recall trials as the paper's analysis takes them (spares included).
  const bool paper = session::isPaperDesign(study);
  const std::map<std::int64_t, int> paper_recall = paper ? paperRecallTrials(db) : std::map<std::int64_t, int>{};
  std::vector<DesignTrialScore> scores;
  std::map<std::tuple<std::string, std::string, std::string, std::string>, int> in_phase;
  for (const session::TrialRecord& t : db.trials()) {
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
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
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
    out[name] = it->second == "NA" || end == it->second.c_str() ? kNaN : v;
  }
  if (!out.empty()) return out;
  const nlohmann::json k = analysis::toJson(analysis::trialKinematics(profile));
  for (const char* name : analysis::kinematicsNames()) out[name] = k.at(name).is_null() ? kNaN : k.at(name).get<double>();
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
      analysis::DataTable t{{{"subject", {}, {}}, {kind, {}, {}}, {m.metric, {}, {}}}, "the " + phase + " trials"};
      std::map<std::pair<std::string, std::string>, int> per_cell;
      std::map<std::string, std::set<std::string>> conditions_of;
      for (const DesignTrialScore& s : a.scores) {
        if (s.phase != phase) continue;
        t.columns[0].text.push_back(s.subject);
        t.columns[1].text.push_back(s.condition);
        t.columns[2].numbers.push_back(shape ? s.shape() : s.force());
        ++per_cell[{s.subject, s.condition}];
        conditions_of[s.subject].insert(s.condition);
      }
      const bool within = std::any_of(conditions_of.begin(), conditions_of.end(), [](const auto& e) { return e.second.size() > 1; });
      const bool replicated = std::any_of(per_cell.begin(), per_cell.end(), [](const auto& e) { return e.second > 1; });
      const std::string formula = fmt::format("{} ~ {} + (1 | subject){}", m.metric, kind,
                                              within && replicated ? fmt::format(" + (1 | subject:{})", kind) : "");
      try {
        m.fit = analysis::fitLmm(t, formula, {.reference = {{kind, m.reference}}});
      } catch (const Error& e) {  // data the model cannot take: said, and the rest of the analysis goes on
        m.skipped = e.what();
      }
      a.models.push_back(std::move(m));
    }
  }
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

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json kinematicsJson(const std::map<std::string, double>& k) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [name, v] : k) out[name] = number(v);
  return out;
}

nlohmann::json meanJson(const SubjectMean& m) {
  return {{"subjects", m.subjects}, {"mean", number(m.mean)}, {"ci95", number(m.ci)}};
}

std::string cell(double v) { return std::isfinite(v) ? fmt::format("{}", v) : ""; }

}  // namespace

SubjectMean meanOverSubjects(const std::vector<double>& values) {
  if (values.empty()) return {0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  const auto [mean, ci] = detail::meanWithCi(values);
  return {static_cast<int>(values.size()), mean, ci};
}

analysis::OneWayData groupSubjectMeans(const std::vector<const DesignTrialScore*>& scores, bool shape) {
  std::map<std::string, std::pair<std::string, std::vector<double>>> by_subject;
  for (const auto* s : scores) {
    auto& [group, values] = by_subject[s->subject];
    group = s->group;
    values.push_back(shape ? s->shape() : s->force());
  }
  analysis::OneWayData data;
  for (const auto& [subject, entry] : by_subject) {
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
  std::vector<DesignTrialScore> completed = completedTrials(db, a);
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
  a.reason = chooseAnalysis(db).reason;
  if (a.subjects == 1 && a.reason.rfind("one learner", 0) != 0) {  // the others' trials all excluded
    a.reason = "one learner (1 subject with analyzed trials): there are no between-subject statistics";
  }
  tabulateCurvesAndCells(a);
  tabulateRetention(a);
  tabulateTransfer(a);
  fitPhaseModels(a);
  fitCurves(a);
  tabulateLearner(a);
  // Rows in the study's order of conditions.
  const auto rank = [&a](const std::string& c) { return std::find(a.conditions.begin(), a.conditions.end(), c) - a.conditions.begin(); };
  std::stable_sort(a.retention.begin(), a.retention.end(),
                   [&](const RetentionRow& x, const RetentionRow& y) { return rank(x.condition) < rank(y.condition); });
  std::stable_sort(a.transfer.begin(), a.transfer.end(),
                   [&](const TransferRow& x, const TransferRow& y) { return rank(x.condition) < rank(y.condition); });
  return a;
}

nlohmann::json designAnalysisToJson(const DesignAnalysis& a) {
  nlohmann::json scores = nlohmann::json::array(), curves = nlohmann::json::array(), cells = nlohmann::json::array(),
                 retention = nlohmann::json::array(), transfer = nlohmann::json::array();
  const auto trialJson = [](const DesignTrialScore& s) {
    nlohmann::json j{{"trial_id", s.trial_id}, {"subject", s.subject}, {"condition", s.condition}, {"group", s.group},
                     {"strategy", s.strategy}, {"session", s.session}, {"day", s.day}, {"block", s.block},
                     {"phase", s.phase}, {"skill", s.skill}, {"trial", s.trial}, {"trial_in_phase", s.trial_in_phase},
                     {"shape", s.shape()}, {"force", s.force()}, {"z", s.score.z}, {"disturbed", s.disturbed},
                     {"kinematics", kinematicsJson(s.kinematics)}};
    if (!s.left_out.empty()) j["left_out"] = s.left_out;
    return j;
  };
  nlohmann::json left_out = nlohmann::json::array();
  for (const auto& s : a.scores) scores.push_back(trialJson(s));
  for (const auto& s : a.left_out) left_out.push_back(trialJson(s));
  for (const auto& c : a.curves) {
    curves.push_back({{"condition", c.condition}, {"phase", c.phase}, {"trial_in_phase", c.trial_in_phase},
                      {"shape", meanJson(c.shape)}, {"force", meanJson(c.force)}});
  }
  for (const auto& c : a.cells) {
    cells.push_back({{"condition", c.condition}, {"session", c.session}, {"phase", c.phase}, {"skill", c.skill},
                     {"shape", meanJson(c.shape)}, {"force", meanJson(c.force)}});
  }
  for (const auto& r : a.retention) {
    retention.push_back({{"condition", r.condition}, {"skill", r.skill}, {"before", r.before},
                         {"shape", {{"before", meanJson(r.shape_before)}, {"retention", meanJson(r.shape_retention)},
                                    {"change", meanJson(r.shape_change)}}},
                         {"force", {{"before", meanJson(r.force_before)}, {"retention", meanJson(r.force_retention)},
                                    {"change", meanJson(r.force_change)}}}});
  }
  for (const auto& t : a.transfer) {
    transfer.push_back({{"condition", t.condition}, {"skill", t.skill}, {"shape", meanJson(t.shape)},
                        {"force", meanJson(t.force)}});
  }
  nlohmann::json models = nlohmann::json::array(), fits = nlohmann::json::array(), learner = nlohmann::json::array();
  for (const PhaseModel& m : a.models) {
    models.push_back({{"phase", m.phase}, {"metric", m.metric}, {"reference", m.reference},
                      {"fit", m.skipped.empty() ? analysis::toJson(m.fit) : nlohmann::json(nullptr)}, {"skipped", m.skipped}});
  }
  for (const CurveFitRow& f : a.fits) {
    fits.push_back({{"condition", f.condition}, {"phase", f.phase}, {"subject", f.subject}, {"metric", f.metric},
                    {"exponential", analysis::toJson(f.exponential)}, {"power", analysis::toJson(f.power)}});
  }
  for (const LearnerRow& r : a.learner) {
    learner.push_back({{"condition", r.condition}, {"phase", r.phase}, {"skill", r.skill}, {"trials", r.trials},
                       {"first", number(r.first)}, {"best", number(r.best)}, {"best_trial", r.best_trial},
                       {"latest", number(r.latest)}, {"mean", number(r.mean)}});
  }
  nlohmann::json subject_scores = nlohmann::json::array();
  for (const SubjectScore& x : a.subject_scores) {
    subject_scores.push_back({{"subject", x.subject}, {"condition", x.condition}, {"skill", x.skill}, {"score", x.score},
                              {"shape", number(x.shape)}, {"force", number(x.force)}});
  }
  const char* design = a.subjects == 1 ? "one-learner" : a.paper_design ? "paper-incomplete" : "groups-and-sessions";
  return {{"design", design}, {"analysis", a.reason}, {"subjects", a.subjects},
          {"subject_scores", subject_scores},
          {"summary", designSummary(a)}, {"models", models}, {"curve_fits", fits}, {"learner", learner},
          {"condition_kind", a.condition_kind}, {"conditions", a.conditions},
          {"phases", a.phases}, {"trials_planned", a.trials_planned}, {"trials_pending", a.trials_pending},
          {"trials_excluded", a.trials_excluded}, {"trials_flagged", a.trials_flagged},
          {"disturbed_policy", a.disturbed_policy}, {"trial_scores", scores}, {"trials_left_out", left_out}, {"curves", curves}, {"phase_cells", cells},
          {"retention", retention}, {"transfer", transfer}, {"conclusions", designConclusions(a)}};
}

void writeDesignCsv(const DesignAnalysis& a, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  writeTrialsCsv(a, dir / "trials.csv");
  const auto means = [](const SubjectMean& m) {
    return std::vector<std::string>{fmt::format("{}", m.subjects), cell(m.mean), cell(m.ci)};
  };
  const auto join = [](std::vector<std::string> row, const std::vector<std::string>& more) {
    row.insert(row.end(), more.begin(), more.end());
    return row;
  };
  io::Table curves{{"condition", "phase", "trial_in_phase", "subjects", "shape_mean", "shape_ci95", "force_subjects",
                    "force_mean", "force_ci95"},
                   {}, ""};
  for (const auto& c : a.curves) {
    curves.rows.push_back(join(join({c.condition, c.phase, fmt::format("{}", c.trial_in_phase)}, means(c.shape)),
                               means(c.force)));
  }
  io::writeTable(curves, dir / "curves.csv", true);
  io::Table cells{{"condition", "session", "phase", "skill", "subjects", "shape_mean", "shape_ci95", "force_subjects",
                   "force_mean", "force_ci95"},
                  {}, ""};
  for (const auto& c : a.cells) {
    cells.rows.push_back(join(join({c.condition, fmt::format("{}", c.session), c.phase, c.skill}, means(c.shape)),
                              means(c.force)));
  }
  io::writeTable(cells, dir / "phases.csv", true);
  io::Table retention{{"condition", "skill", "before", "subjects", "shape_before", "shape_before_ci95", "shape_subjects",
                       "shape_retention", "shape_retention_ci95", "shape_change_subjects", "shape_change",
                       "shape_change_ci95", "force_subjects", "force_change", "force_change_ci95"},
                      {}, ""};
  for (const auto& r : a.retention) {
    retention.rows.push_back(join(join(join(join({r.condition, r.skill, r.before}, means(r.shape_before)),
                                            means(r.shape_retention)),
                                       means(r.shape_change)),
                                  means(r.force_change)));
  }
  io::writeTable(retention, dir / "retention.csv", true);
  io::Table transfer{{"condition", "skill", "subjects", "shape_mean", "shape_ci95", "force_subjects", "force_mean",
                      "force_ci95"},
                     {}, ""};
  for (const auto& t : a.transfer) transfer.rows.push_back(join(join({t.condition, t.skill}, means(t.shape)), means(t.force)));
  io::writeTable(transfer, dir / "transfer.csv", true);

  // The mixed models: each term's F test, then each coefficient with its 95 % interval.
  io::Table models{{"phase", "metric", "formula", "kind", "name", "estimate", "std_error", "lower", "upper", "num_df",
                    "den_df", "statistic", "p", "singular", "skipped"},
                   {}, ""};
  for (const PhaseModel& m : a.models) {
    if (!m.skipped.empty()) {
      models.rows.push_back({m.phase, m.metric, "", "", "", "", "", "", "", "", "", "", "", "", io::plainCell(m.skipped)});
      continue;
    }
    const std::string singular = m.fit.singular ? "1" : "0";
    for (const auto& t : m.fit.terms) {
      models.rows.push_back({m.phase, m.metric, m.fit.formula, "term", t.term, "", "", "", "", cell(t.num_df),
                             cell(t.den_df), cell(t.f), cell(t.p), singular, ""});
    }
    for (const auto& c : m.fit.fixed) {
      models.rows.push_back({m.phase, m.metric, m.fit.formula, "coefficient", c.name, cell(c.estimate), cell(c.std_error),
                             cell(c.lower), cell(c.upper), "", cell(c.df), cell(c.t), cell(c.p), singular, ""});
    }
  }
  io::writeTable(models, dir / "models.csv", true);
  io::Table fits{{"condition", "phase", "subject", "metric", "law", "asymptote", "asymptote_lower", "asymptote_upper",
                  "amplitude", "amplitude_lower", "amplitude_upper", "rate", "rate_lower", "rate_upper", "rss", "points", "note"},
                 {}, ""};
  for (const CurveFitRow& f : a.fits) {
    for (const analysis::CurveFit* fit : {&f.exponential, &f.power}) {
      fits.rows.push_back({f.condition, f.phase, f.subject, f.metric, analysis::curveLawName(fit->law),
                           cell(fit->asymptote.estimate), cell(fit->asymptote.lower), cell(fit->asymptote.upper),
                           cell(fit->amplitude.estimate), cell(fit->amplitude.lower), cell(fit->amplitude.upper),
                           cell(fit->rate.estimate), cell(fit->rate.lower), cell(fit->rate.upper), cell(fit->rss),
                           fmt::format("{}", fit->points), io::plainCell(fit->note)});
    }
  }
  io::writeTable(fits, dir / "curve_fits.csv", true);
  io::Table subject_scores{{"subject", "condition", "skill", "score", "shape", "force"}, {}, ""};
  for (const SubjectScore& x : a.subject_scores) {
    subject_scores.rows.push_back({x.subject, x.condition, x.skill, x.score, cell(x.shape), cell(x.force)});
  }
  io::writeTable(subject_scores, dir / "subject_scores.csv", true);
}

void writeTrialsCsv(const session::StudyDatabase& db, const StudyAnalysis& balanced, AnalysisOptions options,
                    const std::filesystem::path& file) {
  std::map<std::int64_t, analysis::TrialScore> scored;
  for (const auto& c : balanced.costs) scored[c.trial_id] = c.score;
  options.scored = &scored;
  options.kinematics_of_scored = true;
  writeTrialsCsv(analyzeDesign(db, options), file);
}

void writeTrialsCsv(const DesignAnalysis& a, const std::filesystem::path& file) {
  std::vector<std::string> header{"trial_id", "subject", "condition", "group", "strategy", "session", "day", "block",
                                  "phase", "skill", "trial", "trial_in_phase", "x", "y", "z", "fx", "fy", "fz", "shape",
                                  "force"};
  for (const char* name : analysis::kinematicsNames()) header.emplace_back(name);
  for (const char* name : {"disturbed", "analyzed", "left_out"}) header.emplace_back(name);
  // Analyzed and left-out trials together, in the study's order.
  std::vector<const DesignTrialScore*> trials;
  for (const auto* list : {&a.scores, &a.left_out}) {
    for (const auto& s : *list) trials.push_back(&s);
  }
  std::sort(trials.begin(), trials.end(), [](const auto* x, const auto* y) { return x->trial_id < y->trial_id; });
  io::Table table{header, {}, ""};
  for (const DesignTrialScore* p : trials) {
    const DesignTrialScore& s = *p;
    const analysis::TrialScore& c = s.score;
    std::vector<std::string> row{fmt::format("{}", s.trial_id), s.subject, s.condition, s.group, s.strategy,
                                 fmt::format("{}", s.session), fmt::format("{}", s.day), fmt::format("{}", s.block), s.phase,
                                 s.skill, fmt::format("{}", s.trial), fmt::format("{}", s.trial_in_phase), cell(c.x), cell(c.y),
                                 cell(c.z), cell(c.fx), cell(c.fy), cell(c.fz), cell(s.shape()), cell(s.force())};
    for (const char* name : analysis::kinematicsNames()) {
      const auto it = s.kinematics.find(name);
      row.push_back(it == s.kinematics.end() ? "" : cell(it->second));
    }
    row.push_back(io::plainCell(s.disturbed));
    row.emplace_back(s.left_out.empty() ? "1" : "0");
    row.push_back(io::plainCell(s.left_out));
    table.rows.push_back(std::move(row));
  }
  std::filesystem::create_directories(file.parent_path());
  io::writeTable(table, file, true);
}

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

}  // namespace hattr::report

namespace hattr::report {
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
