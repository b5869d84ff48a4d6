#include "hattr/report/study_analysis.hpp"

#include <algorithm>
#include <thread>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/io/table_csv.hpp"

namespace hattr::report {
namespace {

constexpr std::array<Channel, 3> kPositionChannels{Channel::kX, Channel::kY, Channel::kZ};
constexpr std::array<Channel, 3> kForceChannels{Channel::kFx, Channel::kFy, Channel::kFz};

/// The recall trials to analyze, each with its profile's channels preprocessed onto the
/// expert's time steps.
struct Prepared {
  TrialCost cost;
  std::array<std::vector<double>, 6> series;
};

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

}  // namespace

StudyAnalysis analyzeStudy(const session::StudyDatabase& db, const AnalysisOptions& options) {
  const session::StudyDefinition& study = db.study();
  const HapticProfile expert = db.expert(study.skill);
  const std::vector<double> expert_t = expert.channel(Channel::kTime);

  // The expert's series, normalized once.
  std::array<std::vector<double>, 6> expert_series;
  for (std::size_t k = 0; k < 6; ++k) {
    const Channel c = k < 3 ? kPositionChannels[k] : kForceChannels[k - 3];
    expert_series[k] = analysis::normalize(expert.channel(c), options.normalization);
  }

  // Every completed recall trial, preprocessed onto the expert's time steps.
  std::vector<Prepared> prepared;
  std::vector<std::string> missing;
  for (const session::TrialRecord& t : db.trials()) {
    if (t.plan.phase != session::Phase::kRecall) continue;
    if (t.status != session::TrialStatus::kCompleted) {
      missing.push_back(fmt::format("{} {} recall {}", t.plan.subject, guidance::modeName(t.plan.mode), t.plan.index));
      continue;
    }
    const HapticProfile trial = db.trialProfile(t.id);
    Prepared p;
    p.cost = {t.id, t.plan.subject, std::string(guidance::modeName(t.plan.mode)), t.plan.index, {}, {}};
    const std::vector<double> trial_t = trial.channel(Channel::kTime);
    for (std::size_t k = 0; k < 6; ++k) {
      const Channel c = k < 3 ? kPositionChannels[k] : kForceChannels[k - 3];
      p.series[k] = analysis::preprocessTrial(trial_t, trial.channel(c), expert_t, options.normalization);
    }
    prepared.push_back(std::move(p));
  }
  HATTR_THROW_UNLESS(missing.empty(), "{}: {} recall trial{} not completed yet ({}{}); run the study first",
                     db.file().string(), missing.size(), missing.size() == 1 ? " is" : "s are", missing.front(),
                     missing.size() > 1 ? ", ..." : "");
  HATTR_THROW_UNLESS(!prepared.empty(), "{}: the study has no recall trials to analyze", db.file().string());

  // DTW per channel, all trials of a channel as one batch, the channels shared by the threads.
  const analysis::DtwOptions dtw{.cost = options.cost, .band_fraction = options.band_fraction};
  std::array<std::vector<double>, 6> costs;
  const auto channelCosts = [&](std::size_t k) {
    std::vector<std::vector<double>> a(prepared.size(), expert_series[k]);
    std::vector<std::vector<double>> b;
    b.reserve(prepared.size());
    for (const auto& p : prepared) b.push_back(p.series[k]);
    costs[k] = analysis::dtwBatch(a, b, dtw);
  };
  {
    std::vector<std::thread> workers;
    const unsigned threads = std::max(1u, options.threads);
    for (unsigned w = 0; w < threads; ++w) {
      workers.emplace_back([&, w] {
        for (std::size_t k = w; k < 6; k += threads) channelCosts(k);
      });
    }
    for (auto& t : workers) t.join();
  }

  StudyAnalysis out;
  out.options = options;
  for (std::size_t i = 0; i < prepared.size(); ++i) {
    TrialCost c = prepared[i].cost;
    for (std::size_t k = 0; k < 3; ++k) {
      c.position[k] = costs[k][i];
      c.force[k] = costs[k + 3][i];
    }
    out.costs.push_back(c);
  }
  out.trajectory = analyzeMetric("trajectory", out.costs, true);
  out.force = analyzeMetric("force", out.costs, false);
  return out;
}

namespace {

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json anovaJson(const analysis::AnovaTable& t) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : t.rows) {
    rows.push_back({{"source", r.source}, {"df", r.df}, {"ss", r.sum_sq}, {"ms", r.mean_sq}, {"f", number(r.f)},
                    {"p", number(r.p)}, {"partial_eta_sq", number(r.partial_eta_sq)}, {"error_term", r.error_term}});
  }
  return rows;
}

nlohmann::json metricJson(const MetricResult& m) {
  nlohmann::json per_mode = nlohmann::json::object();
  for (const auto& [mode, table] : m.per_mode) per_mode[mode] = anovaJson(table);
  nlohmann::json stats = nlohmann::json::object();
  for (const auto& g : m.per_mode_stats) {
    stats[g.a_level] = {{"n", g.stats.count}, {"mean", g.stats.mean}, {"variance", number(g.stats.variance)},
                        {"sd", number(g.stats.sd)}};
  }
  for (const auto& v : m.inter_subject) stats[v.level]["inter_subject_variance"] = number(v.variance);
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
                     {"x", c.position[0]}, {"y", c.position[1]}, {"z", c.position[2]}, {"fx", c.force[0]},
                     {"fy", c.force[1]}, {"fz", c.force[2]}, {"trajectory", c.trajectory()},
                     {"force", c.forceProfile()}});
  }
  const char* norm = a.options.normalization == analysis::Normalization::kPaper    ? "paper"
                     : a.options.normalization == analysis::Normalization::kZScore ? "zscore"
                                                                                    : "none";
  return {{"options",
           {{"normalization", norm}, {"cost_fn", a.options.cost == analysis::DtwCost::kAbsolute ? "abs" : "sq"},
            {"band", number(a.options.band_fraction < 0 ? NAN : a.options.band_fraction)}}},
          {"recall_costs", costs},
          {"trajectory", metricJson(a.trajectory)},
          {"force", metricJson(a.force)}};
}

void storeAnalysis(session::StudyDatabase& db, const StudyAnalysis& a) { db.putResult("analysis", analysisToJson(a).dump()); }

void writeAnalysisCsv(const StudyAnalysis& a, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  io::Table costs{{"trial_id", "subject", "mode", "trial", "x", "y", "z", "fx", "fy", "fz", "trajectory", "force"}, {}, ""};
  for (const auto& c : a.costs) {
    costs.rows.push_back({fmt::format("{}", c.trial_id), c.subject, c.mode, fmt::format("{}", c.trial),
                          fmt::format("{}", c.position[0]), fmt::format("{}", c.position[1]), fmt::format("{}", c.position[2]),
                          fmt::format("{}", c.force[0]), fmt::format("{}", c.force[1]), fmt::format("{}", c.force[2]),
                          fmt::format("{}", c.trajectory()), fmt::format("{}", c.forceProfile())});
  }
  io::writeTable(costs, dir / "recall_costs.csv", true);

  io::Table anova{{"metric", "model", "source", "df", "ss", "ms", "f", "p", "partial_eta_sq"}, {}, ""};
  const auto add = [&anova](const std::string& metric, const std::string& model, const analysis::AnovaTable& t) {
    for (const auto& r : t.rows) {
      anova.rows.push_back({metric, model, r.source, fmt::format("{}", r.df), fmt::format("{}", r.sum_sq),
                            fmt::format("{}", r.mean_sq), std::isfinite(r.f) ? fmt::format("{}", r.f) : "",
                            std::isfinite(r.p) ? fmt::format("{}", r.p) : "",
                            std::isfinite(r.partial_eta_sq) ? fmt::format("{}", r.partial_eta_sq) : ""});
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
