#include "hattr/report/study_analysis.hpp"

#include <algorithm>
#include <limits>
#include <map>
#include <set>

#include <fmt/format.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/io/table_csv.hpp"

namespace hattr::report {

MetricResult analyzeMetric(const std::string& name, const std::vector<TrialCost>& costs, bool trajectory) {
  MetricResult r;
  r.metric = name;
  const auto value = [trajectory](const TrialCost& c) { return trajectory ? c.trajectory() : c.forceProfile(); };

  // Overall: mode × subject with the recall trials as replicates; subject random.
  analysis::TwoWayData all{"mode", "subject", {}, {}, {}};
  for (const auto& c : costs) {
    all.a.push_back(c.mode);
    all.b.push_back(c.subject);
    all.y.push_back(value(c));
  }
  const analysis::AnovaOptions mixed{.b_random = true};
  r.overall = analysis::twoWayAnova(all, mixed);
  if (r.overall.a_levels.size() >= 2 && r.overall.b_levels.size() >= 3) {
    r.tukey = analysis::tukeyHsd(all, analysis::Factor::kA, mixed);
  }
  r.per_mode_stats = analysis::describeGroups(all, analysis::Grouping::kA);
  r.inter_subject = analysis::interSubjectVariance(all);

  // Per mode: trial × subject, one observation per cell (the additive model).
  for (const auto& mode : r.overall.a_levels) {
    analysis::TwoWayData d{"trial", "subject", {}, {}, {}};
    std::map<int, std::pair<double, int>> by_trial;
    for (const auto& c : costs) {
      if (c.mode != mode) continue;
      d.a.push_back(fmt::format("{}", c.trial));
      d.b.push_back(c.subject);
      d.y.push_back(value(c));
      by_trial[c.trial].first += value(c);
      ++by_trial[c.trial].second;
    }
    if (by_trial.size() >= 2) r.per_mode.emplace(mode, analysis::twoWayAnova(d));
    for (const auto& [trial, sum] : by_trial) r.mean_by_trial[mode].push_back(sum.first / sum.second);
  }

  // Table 1: each subject's mode with the lowest mean cost.
  std::map<std::string, std::map<std::string, std::pair<double, int>>> sums;
  for (const auto& c : costs) {
    auto& s = sums[c.subject][c.mode];
    s.first += value(c);
    ++s.second;
  }
  for (const auto& [subject, modes] : sums) {
    const auto best = std::min_element(modes.begin(), modes.end(), [](const auto& a, const auto& b) {
      return a.second.first / a.second.second < b.second.first / b.second.second;
    });
    r.best_mode[subject] = best->first;
  }
  return r;
}

namespace {

/// The analyzed recall trials (unscored), the flagged and the spares used, into `out`; returns
/// what keeps the balanced design from being complete, each a sentence (none: complete).
std::vector<std::string> selectRecallTrials(const session::StudyDatabase& db,
                                            const std::vector<session::TrialRecord>& records, StudyAnalysis& out) {
  const session::StudyDefinition& study = db.study();
  const std::set<int> analyzed(out.analyzed_recall_trials.begin(), out.analyzed_recall_trials.end());
  const bool exclude_disturbed = study.protocol.disturbed == session::DisturbedPolicy::kExclude;

  // The analyzed recall trials (all must be completed); disturbed ones flagged. With the
  // "exclude" policy a disturbed trial is left out and a clean recall trial outside the
  // analyzed set of the same subject and mode (a spare, lowest number first) takes its place
  // and its trial number, so the design stays balanced.
  std::map<std::pair<std::string, std::string>, std::vector<const session::TrialRecord*>> spares;
  std::map<std::pair<std::string, std::string>, std::vector<int>> excluded;
  std::vector<std::string> missing;
  for (const session::TrialRecord& t : records) {
    if (t.plan.phase != session::kPhaseRecall) continue;
    const std::string mode(guidance::modeName(t.plan.mode));
    const bool done = t.status == session::TrialStatus::kCompleted;
    if (!analyzed.contains(t.plan.index)) {
      if (done && t.disturbed.empty()) spares[{t.plan.subject, mode}].push_back(&t);
      continue;
    }
    if (!done) {
      missing.push_back(fmt::format("{} {} recall {}", t.plan.subject, mode, t.plan.index));
      continue;
    }
    const bool keep = t.disturbed.empty() || !exclude_disturbed;
    if (!t.disturbed.empty()) {
      out.flagged.push_back({t.id, t.plan.subject, mode, t.plan.index, t.disturbed, t.disturbed_attempts, keep});
    }
    if (keep) {
      out.costs.push_back({t.id, t.plan.subject, mode, t.plan.index, {}, t.disturbed});
    } else {
      excluded[{t.plan.subject, mode}].push_back(t.plan.index);
    }
  }
  std::vector<std::string> problems;
  if (!missing.empty()) {
    problems.push_back(fmt::format("{}: {} recall trial{} not completed yet ({}{})", db.file().string(), missing.size(),
                                   missing.size() == 1 ? " is" : "s are", missing.front(), missing.size() > 1 ? ", ..." : ""));
  }
  for (const auto& [cell, places] : excluded) {
    const auto& candidates = spares[cell];
    const int count = static_cast<int>(places.size());
    if (static_cast<int>(candidates.size()) < count) {
      problems.push_back(fmt::format(
          "{}: subject {} {}: {} disturbed recall trial{} excluded (protocol.disturbed_trials \"exclude\") but {} clean "
          "spare{} outside the analyzed trials; the balanced design needs every cell: use \"repeat\" or \"flag\", or "
          "analyze fewer recall trials",
          db.file().string(), cell.first, cell.second, count, count == 1 ? " is" : "s are", candidates.size(),
          candidates.size() == 1 ? "" : "s"));
      continue;
    }
    for (int k = 0; k < count; ++k) {
      const session::TrialRecord& t = *candidates[static_cast<std::size_t>(k)];
      out.costs.push_back({t.id, t.plan.subject, cell.second, places[static_cast<std::size_t>(k)], {}, ""});
      out.spares_used.push_back(t.id);
    }
  }
  return problems;
}

}  // namespace

AnalysisChoice chooseAnalysis(const session::StudyDatabase& db) { return chooseAnalysis(db, db.trials()); }

AnalysisChoice chooseAnalysis(const session::StudyDatabase& db, const std::vector<session::TrialRecord>& records) {
  std::set<std::string> subjects;
  for (const session::TrialRecord& t : records) {
    if (t.status == session::TrialStatus::kCompleted) subjects.insert(t.plan.subject);
  }
  if (subjects.size() < 2) {
    return {false, fmt::format("one learner ({} subject with completed trials): there are no between-subject statistics, "
                               "so the report shows the learner's curves, sessions, best and latest scores",
                               subjects.size())};
  }
  if (!session::isPaperDesign(db.study())) {
    return {false, "the study has groups, sessions or phases beyond the paper's: each phase with two conditions or "
                   "more is compared by a linear mixed model of its trials (subjects random), as docs/analysis.md "
                   "describes"};
  }
  StudyAnalysis probe;
  probe.analyzed_recall_trials = session::analyzedRecallTrials(db.study().protocol);
  const std::vector<std::string> problems = selectRecallTrials(db, records, probe);
  if (!problems.empty()) {
    return {false, fmt::format("the paper's design is not complete ({}), and the balanced ANOVA needs every cell: a "
                               "linear mixed model analyzes the trials there are", problems.front())};
  }
  return {true, "the paper's design, complete: the balanced two-way ANOVA of mode × subject (subjects random, mode "
                "tested against mode × subject), as the paper analyzes it"};
}

std::map<std::int64_t, int> paperRecallTrials(const session::StudyDatabase& db) {
  return paperRecallTrials(db, db.trials());
}

std::map<std::int64_t, int> paperRecallTrials(const session::StudyDatabase& db,
                                              const std::vector<session::TrialRecord>& records) {
  StudyAnalysis probe;
  probe.analyzed_recall_trials = session::analyzedRecallTrials(db.study().protocol);
  (void)selectRecallTrials(db, records, probe);  // what is missing only makes the set smaller
  std::map<std::int64_t, int> out;
  for (const TrialCost& c : probe.costs) out[c.trial_id] = c.trial;
  return out;
}

StudyAnalysis analyzeStudy(const session::StudyDatabase& db, const AnalysisOptions& options) {
  const session::StudyDefinition& study = db.study();
  HATTR_THROW_UNLESS(session::isPaperDesign(study),
                     "{}: the paper's analysis (recall trials per mode, the balanced ANOVA) is for the paper's design; "
                     "this study has groups and sessions: `hattr study analyze` analyzes it as its design says "
                     "(report::analyzeDesign)",
                     db.file().string());
  StudyAnalysis out;
  out.options = options;
  out.options.progress = nullptr;  // the caller's callback does not outlive the call
  for (const auto mode : study.modes) out.modes.emplace_back(guidance::modeName(mode));
  out.analyzed_recall_trials = session::analyzedRecallTrials(study.protocol);
  out.disturbed_policy = std::string(session::disturbedPolicyName(study.protocol.disturbed));
  const std::vector<std::string> problems = selectRecallTrials(db, db.trials(), out);
  if (!problems.empty()) {
    throw InputError(problems.front() + (problems.front().find("not completed") != std::string::npos ? "; run the study first" : ""));
  }
  HATTR_THROW_UNLESS(!out.costs.empty(), "{}: the study has no recall trials to analyze", db.file().string());

  // One scorer, as `hattr dtw --score` and the studio use it; the trials are loaded and
  // scored a chunk at a time (bounded memory, and progress between chunks).
  const analysis::TrialScorer scorer(db.expert(study.skill), {.normalization = options.normalization,
                                                              .cost = options.cost,
                                                              .band_fraction = options.band_fraction,
                                                              .score_shape = options.analyze_trajectory,
                                                              .score_force = options.analyze_force});
  // A chunk is whole SIMD blocks of the DTW batch kernel (32 pairs or more): no idle lanes.
  const std::size_t width = analysis::dtwBatchWidth();
  const std::size_t chunk = (32 + width - 1) / width * width;
  const int total = static_cast<int>(out.costs.size());
  if (options.progress) options.progress(0, total);
  for (std::size_t first = 0; first < out.costs.size(); first += chunk) {
    const std::size_t last = std::min(out.costs.size(), first + chunk);
    std::vector<std::size_t> unscored;
    for (std::size_t i = first; i < last; ++i) {
      if (const auto* known = options.scoredAlready(out.costs[i].trial_id)) {
        out.costs[i].score = *known;
      } else {
        unscored.push_back(i);
      }
    }
    std::vector<HapticProfile> profiles;
    for (const std::size_t i : unscored) profiles.push_back(db.trialProfile(out.costs[i].trial_id));
    std::vector<const HapticProfile*> pointers;
    for (const auto& p : profiles) pointers.push_back(&p);
    const std::vector<analysis::TrialScore> scores = scorer.scoreAll(pointers, options.threads);
    for (std::size_t k = 0; k < unscored.size(); ++k) out.costs[unscored[k]].score = scores[k];
    if (options.progress) options.progress(static_cast<int>(last), total);
  }
  out.trajectory.metric = "trajectory";
  out.force.metric = "force";
  if (options.analyze_trajectory) out.trajectory = analyzeMetric("trajectory", out.costs, true);
  if (options.analyze_force) out.force = analyzeMetric("force", out.costs, false);
  return out;
}

namespace {

nlohmann::json anovaJson(const analysis::AnovaTable& t) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : t.rows) {
    rows.push_back({{"source", r.source}, {"df", r.df}, {"ss", r.sum_sq}, {"ms", r.mean_sq}, {"f", jsonNumber(r.f)},
                    {"p", jsonNumber(r.p)}, {"partial_eta_sq", jsonNumber(r.partial_eta_sq)}, {"error_term", r.error_term}});
  }
  return rows;
}

nlohmann::json metricJson(const MetricResult& m) {
  nlohmann::json per_mode = nlohmann::json::object();
  for (const auto& [mode, table] : m.per_mode) per_mode[mode] = anovaJson(table);
  nlohmann::json stats = nlohmann::json::object();
  for (const auto& g : m.per_mode_stats) {
    stats[g.a_level] = {{"n", g.stats.count}, {"mean", g.stats.mean}, {"variance", jsonNumber(g.stats.variance)},
                        {"sd", jsonNumber(g.stats.sd)}};
  }
  for (const auto& v : m.inter_subject) stats[v.level]["inter_subject_variance"] = jsonNumber(v.variance);
  nlohmann::json tukey = nullptr;
  if (m.tukey) {
    tukey = nlohmann::json::array();
    for (const auto& c : m.tukey->comparisons) {
      tukey.push_back({{"comparison", c.comparison}, {"diff", c.diff}, {"lwr", c.lower}, {"upr", c.upper},
                       {"p_adj", c.p_adjusted}});
    }
  }
  return {{"overall", anovaJson(m.overall)}, {"per_mode", per_mode}, {"tukey", tukey}, {"per_mode_stats", stats},
          {"mean_by_trial", m.mean_by_trial}, {"best_mode", m.best_mode}};
}

}  // namespace

nlohmann::json analysisToJson(const StudyAnalysis& a) {
  nlohmann::json costs = nlohmann::json::array();
  for (const auto& c : a.costs) {
    costs.push_back({{"trial_id", c.trial_id}, {"subject", c.subject}, {"mode", c.mode}, {"trial", c.trial},
                     {"x", c.score.x}, {"y", c.score.y}, {"z", c.score.z}, {"fx", c.score.fx},
                     {"fy", c.score.fy}, {"fz", c.score.fz}, {"trajectory", c.trajectory()},
                     {"force", c.forceProfile()}, {"disturbed", c.disturbed}});
  }
  nlohmann::json flagged = nlohmann::json::array();
  const nlohmann::json spares = a.spares_used;
  for (const auto& f : a.flagged) {
    flagged.push_back({{"trial_id", f.trial_id}, {"subject", f.subject}, {"mode", f.mode}, {"trial", f.trial},
                       {"disturbed", f.disturbed}, {"disturbed_attempts", f.disturbed_attempts},
                       {"analyzed", f.analyzed}});
  }
  return {{"options",
           {{"normalization", analysis::normalizationName(a.options.normalization)},
            {"cost_fn", analysis::dtwCostName(a.options.cost)},
            {"band", jsonNumber(a.options.band_fraction < 0 ? NAN : a.options.band_fraction)}}},
          {"analyzed_recall_trials", a.analyzed_recall_trials},
          {"disturbed_policy", a.disturbed_policy},
          {"flagged_trials", flagged},
          {"spare_trials_used", spares},
          {"recall_costs", costs},
          {"trajectory", metricJson(a.trajectory)},
          {"force", metricJson(a.force)}};
}

void storeAnalysis(session::StudyDatabase& db, const StudyAnalysis& a) { db.putResult("analysis", analysisToJson(a).dump()); }

std::vector<TrialCost> storedCosts(const session::StudyDatabase& db) {
  const std::optional<std::string> stored = db.result("analysis");
  if (!stored) return {};
  const auto refuse = [](const std::string& why) {
    return InputError(fmt::format("the study's stored analysis (results key \"analysis\"): {}; run `hattr study "
                                  "analyze` again to replace it",
                                  why));
  };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(*stored);
  } catch (const nlohmann::json::exception& e) {
    throw refuse(fmt::format("not JSON ({})", e.what()));
  }
  if (!j.is_object() || !j.contains("recall_costs") || !j["recall_costs"].is_array()) {
    throw refuse("expected an object with an array \"recall_costs\"");
  }
  // A number, or null where the analysis wrote a non-finite one.
  const auto real = [](const nlohmann::json& v) {
    return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>();
  };
  std::vector<TrialCost> costs;
  for (std::size_t i = 0; i < j["recall_costs"].size(); ++i) {
    const nlohmann::json& c = j["recall_costs"][i];
    try {
      TrialCost cost{.trial_id = c.at("trial_id").get<std::int64_t>(),
                     .subject = c.at("subject").get<std::string>(),
                     .mode = c.at("mode").get<std::string>(),
                     .trial = c.at("trial").get<int>(),
                     .score = {},
                     .disturbed = c.at("disturbed").get<std::string>()};
      cost.score.x = real(c.at("x"));
      cost.score.y = real(c.at("y"));
      cost.score.z = real(c.at("z"));
      cost.score.fx = real(c.at("fx"));
      cost.score.fy = real(c.at("fy"));
      cost.score.fz = real(c.at("fz"));
      costs.push_back(std::move(cost));
    } catch (const nlohmann::json::exception& e) {
      throw refuse(fmt::format("recall_costs[{}]: {}", i, e.what()));
    }
  }
  return costs;
}

void writeAnalysisCsv(const StudyAnalysis& a, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  io::Table costs{{"trial_id", "subject", "mode", "trial", "x", "y", "z", "fx", "fy", "fz", "trajectory", "force", "disturbed"},
                  {}, ""};
  for (const auto& c : a.costs) {
    const analysis::TrialScore& s = c.score;
    costs.rows.push_back({fmt::format("{}", c.trial_id), c.subject, c.mode, fmt::format("{}", c.trial),
                          fmt::format("{}", s.x), fmt::format("{}", s.y), fmt::format("{}", s.z),
                          fmt::format("{}", s.fx), fmt::format("{}", s.fy), fmt::format("{}", s.fz),
                          fmt::format("{}", c.trajectory()), fmt::format("{}", c.forceProfile()),
                          io::plainCell(c.disturbed)});
  }
  io::writeTable(costs, dir / "recall_costs.csv", true);

  // Each row with the row it is tested against (error_term): the mode against mode × subject.
  io::Table anova{{"metric", "model", "source", "df", "ss", "ms", "f", "p", "partial_eta_sq", "error_term"}, {}, ""};
  const auto add = [&anova](const std::string& metric, const std::string& model, const analysis::AnovaTable& t) {
    for (const auto& r : t.rows) {
      anova.rows.push_back({metric, model, r.source, fmt::format("{}", r.df), fmt::format("{}", r.sum_sq),
                            fmt::format("{}", r.mean_sq), std::isfinite(r.f) ? fmt::format("{}", r.f) : "",
                            std::isfinite(r.p) ? fmt::format("{}", r.p) : "",
                            std::isfinite(r.partial_eta_sq) ? fmt::format("{}", r.partial_eta_sq) : "", r.error_term});
    }
  };
  for (const MetricResult* m : {&a.trajectory, &a.force}) {
    add(m->metric, "mode x subject", m->overall);
    for (const auto& [mode, t] : m->per_mode) add(m->metric, mode + ": trial x subject", t);
  }
  io::writeTable(anova, dir / "anova.csv", true);

  io::Table table1{{"subject", "best_mode_trajectory", "best_mode_force"}, {}, ""};
  for (const auto& [subject, mode] : a.trajectory.best_mode) table1.rows.push_back({subject, mode, a.force.best_mode.at(subject)});
  io::writeTable(table1, dir / "table1.csv", true);
}

}  // namespace hattr::report
