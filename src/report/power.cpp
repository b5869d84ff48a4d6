#include "hattr/report/power.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/io/profile_csv.hpp"
#include "svg_plot_internal.hpp"

namespace hattr::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kShardFormat = 1;

/// Values per metric in the flat encoding: p, η², then one p per pair.
std::size_t metricSize(const PowerPlan& plan) { return 2 + plan.pairs().size(); }

/// A significant result: a p below α (a NaN p, no variance to test, never is).
bool significant(double p, double alpha) { return std::isfinite(p) && p < alpha; }

/// A number read back from a shard: null (how jsonNumber writes NaN) is NaN again; doubles
/// round-trip exactly (17 significant digits).
double numberOrNaN(const nlohmann::json& v) { return v.is_null() ? kNaN : v.get<double>(); }

nlohmann::json planToJson(const PowerPlan& plan) {
  return {{"study", plan.study},   {"modes", plan.modes}, {"subject_counts", plan.subject_counts},
          {"replicates", plan.replicates}, {"seed", plan.seed}, {"alpha", plan.alpha}};
}

PowerPlan planFromJson(const nlohmann::json& j) {
  PowerPlan plan;
  plan.study = j.at("study");
  plan.modes = j.at("modes").get<std::vector<std::string>>();
  plan.subject_counts = j.at("subject_counts").get<std::vector<int>>();
  plan.replicates = j.at("replicates").get<int>();
  plan.seed = j.at("seed").get<std::uint64_t>();
  plan.alpha = j.at("alpha").get<double>();
  return plan;
}

nlohmann::json proportionJson(const analysis::Proportion& p) {
  return {{"significant", p.successes}, {"replicates", p.trials}, {"power", p.estimate},
          {"ci95", {p.lower, p.upper}}};
}

}  // namespace

std::vector<std::string> PowerPlan::pairs() const {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < modes.size(); ++i) {
    for (std::size_t j = i + 1; j < modes.size(); ++j) out.push_back(modes[i] + "-" + modes[j]);
  }
  return out;
}

MetricOutcome metricOutcome(const MetricResult& metric, const PowerPlan& plan) {
  return metricOutcome(metric.overall.row("mode"), metric.tukey, plan);
}

MetricOutcome metricOutcome(const analysis::AnovaRow& effect, const std::optional<analysis::TukeyResult>& tukey,
                            const PowerPlan& plan) {
  MetricOutcome out;
  out.p_mode = effect.p;
  out.partial_eta_sq = effect.partial_eta_sq;
  // Tukey names a pair either way round: look each plan pair up as a set of two modes.
  for (std::size_t i = 0; i < plan.modes.size(); ++i) {
    for (std::size_t j = i + 1; j < plan.modes.size(); ++j) {
      double p = kNaN;
      if (tukey) {
        for (const auto& c : tukey->comparisons) {
          const bool same = (c.level == plan.modes[i] && c.other_level == plan.modes[j]) ||
                            (c.level == plan.modes[j] && c.other_level == plan.modes[i]);
          if (same) p = c.p_adjusted;
        }
      }
      out.p_pairs.push_back(p);
    }
  }
  return out;
}

std::size_t encodedOutcomeSize(const PowerPlan& plan) {
  return 1 + plan.subject_counts.size() * kPowerMetrics.size() * metricSize(plan);
}

void encodeOutcome(const ReplicateOutcome& outcome, std::vector<double>& out) {
  out.push_back(outcome.replicate);
  for (const auto& design : outcome.designs) {
    for (const MetricOutcome& m : design) {
      out.push_back(m.p_mode);
      out.push_back(m.partial_eta_sq);
      out.insert(out.end(), m.p_pairs.begin(), m.p_pairs.end());
    }
  }
}

ReplicateOutcome decodeOutcome(const PowerPlan& plan, std::span<const double> values) {
  HATTR_THROW_UNLESS(values.size() == encodedOutcomeSize(plan), "power: a replicate of {} values: expected {}",
                     values.size(), encodedOutcomeSize(plan));
  ReplicateOutcome out;
  out.replicate = static_cast<int>(values[0]);
  std::size_t at = 1;
  const std::size_t pairs = metricSize(plan) - 2;
  for (std::size_t d = 0; d < plan.subject_counts.size(); ++d) {
    std::array<MetricOutcome, 2> design;
    for (MetricOutcome& m : design) {
      m.p_mode = values[at++];
      m.partial_eta_sq = values[at++];
      m.p_pairs.assign(values.begin() + static_cast<std::ptrdiff_t>(at), values.begin() + static_cast<std::ptrdiff_t>(at + pairs));
      at += pairs;
    }
    out.designs.push_back(std::move(design));
  }
  return out;
}

PowerTable summarizePower(const PowerPlan& plan, std::vector<ReplicateOutcome> outcomes) {
  // Every replicate once: the summary is then the same whatever ran them, in whatever order.
  std::sort(outcomes.begin(), outcomes.end(), [](const auto& a, const auto& b) { return a.replicate < b.replicate; });
  for (std::size_t i = 0; i < outcomes.size(); ++i) {
    const int r = outcomes[i].replicate;
    HATTR_THROW_UNLESS(r >= 0 && r < plan.replicates, "power: replicate {}: expected 0 to {}", r, plan.replicates - 1);
    HATTR_THROW_UNLESS(i == 0 || outcomes[i - 1].replicate != r, "power: replicate {} is there twice", r);
    HATTR_THROW_UNLESS(outcomes[i].designs.size() == plan.subject_counts.size(),
                       "power: replicate {}: {} designs, expected {}", r, outcomes[i].designs.size(),
                       plan.subject_counts.size());
  }
  HATTR_THROW_UNLESS(static_cast<int>(outcomes.size()) == plan.replicates, "power: {} of {} replicates present",
                     outcomes.size(), plan.replicates);

  PowerTable table{plan, {}};
  const std::vector<std::string> pairs = plan.pairs();
  for (std::size_t d = 0; d < plan.subject_counts.size(); ++d) {
    for (std::size_t m = 0; m < kPowerMetrics.size(); ++m) {
      int found = 0;
      double eta_sum = 0.0;
      int eta_count = 0;
      std::vector<int> pair_found(pairs.size(), 0);
      for (const auto& o : outcomes) {
        const MetricOutcome& x = o.designs[d][m];
        found += significant(x.p_mode, plan.alpha) ? 1 : 0;
        if (std::isfinite(x.partial_eta_sq)) {
          eta_sum += x.partial_eta_sq;
          ++eta_count;
        }
        for (std::size_t k = 0; k < pairs.size(); ++k) pair_found[k] += significant(x.p_pairs[k], plan.alpha) ? 1 : 0;
      }
      PowerRow row{plan.subject_counts[d], kPowerMetrics[m], analysis::clopperPearson(found, plan.replicates),
                   eta_count > 0 ? eta_sum / eta_count : kNaN, {}};
      for (std::size_t k = 0; k < pairs.size(); ++k) {
        row.pairs.push_back({pairs[k], analysis::clopperPearson(pair_found[k], plan.replicates)});
      }
      table.rows.push_back(std::move(row));
    }
  }
  return table;
}

nlohmann::json powerShardToJson(const PowerPlan& plan, int shard, int shards, const std::vector<ReplicateOutcome>& outcomes) {
  nlohmann::json replicates = nlohmann::json::array();
  for (const auto& o : outcomes) {
    std::vector<double> flat;
    encodeOutcome(o, flat);
    nlohmann::json values = nlohmann::json::array();
    for (std::size_t i = 1; i < flat.size(); ++i) values.push_back(jsonNumber(flat[i]));
    replicates.push_back({{"replicate", o.replicate}, {"values", values}});
  }
  return {{"hattr_power_shard", kShardFormat}, {"shard", shard}, {"shards", shards}, {"plan", planToJson(plan)},
          {"outcomes", replicates}};
}

PowerTable mergePowerShards(const std::vector<std::filesystem::path>& files) {
  HATTR_THROW_UNLESS(!files.empty(), "power merge: expected at least one shard file");
  std::optional<PowerPlan> plan;
  std::filesystem::path plan_file;
  std::vector<ReplicateOutcome> outcomes;
  std::map<int, std::filesystem::path> held_by;
  for (const auto& file : files) {
    const std::string where = file.string();
    const nlohmann::json j = parseJsonObject(readTextFile(file), where);
    readingJson(where, [&] {
      HATTR_THROW_UNLESS(j.value("hattr_power_shard", 0) == kShardFormat,
                         "{}: not a power shard (expected \"hattr_power_shard\": {}, as `hattr sim power --shard` writes)",
                         where, kShardFormat);
      const PowerPlan this_plan = planFromJson(j.at("plan"));
      if (!plan) {
        plan = this_plan;
        plan_file = file;
      }
      HATTR_THROW_UNLESS(this_plan == *plan, "{}: another power analysis than {} (their plans differ: study, designs, "
                         "replicates, seed or alpha)", where, plan_file.string());
      for (const auto& entry : j.at("outcomes")) {
        const nlohmann::json& index = entry.at("replicate");
        HATTR_THROW_UNLESS(index.is_number_integer() && index.get<std::int64_t>() >= 0 &&
                               index.get<std::int64_t>() < plan->replicates,
                           "{}: replicate {}: expected a whole number from 0 to {}", where, index.dump(),
                           plan->replicates - 1);
        std::vector<double> flat{index.get<double>()};
        for (const auto& v : entry.at("values")) flat.push_back(numberOrNaN(v));
        HATTR_THROW_UNLESS(flat.size() == encodedOutcomeSize(*plan), "{}: replicate {}: {} values, expected {}", where,
                           entry.at("replicate").dump(), flat.size() - 1, encodedOutcomeSize(*plan) - 1);
        ReplicateOutcome o = decodeOutcome(*plan, flat);
        const auto [it, fresh] = held_by.emplace(o.replicate, file);
        HATTR_THROW_UNLESS(fresh, "{}: replicate {} is also in {}", where, o.replicate, it->second.string());
        outcomes.push_back(std::move(o));
      }
    });
  }
  // Name what is missing before summarizing.
  std::vector<int> missing;
  for (int r = 0; r < plan->replicates && missing.size() < 5; ++r) {
    if (!held_by.contains(r)) missing.push_back(r);
  }
  HATTR_THROW_UNLESS(missing.empty(), "power merge: {} of {} replicates are in the files; missing: {}{} (a shard not merged?)",
                     held_by.size(), plan->replicates, fmt::join(missing, ", "),
                     plan->replicates - static_cast<int>(held_by.size()) > 5 ? ", ..." : "");
  return summarizePower(*plan, std::move(outcomes));
}

nlohmann::json powerTableToJson(const PowerTable& table) {
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : table.rows) {
    nlohmann::json pairs = nlohmann::json::object();
    for (const auto& p : r.pairs) pairs[p.pair] = proportionJson(p.power);
    nlohmann::json row = {{"subjects", r.subjects}, {"metric", r.metric}, {"mode_effect", proportionJson(r.power)},
                          {"mean_partial_eta_sq", jsonNumber(r.mean_partial_eta_sq)}, {"tukey", pairs}};
    rows.push_back(row);
  }
  return {{"plan", planToJson(table.plan)}, {"rows", rows}};
}

std::string powerTableText(const PowerTable& table) {
  const PowerPlan& plan = table.plan;
  // A design of groups and sessions compares one phase (sim::PowerStudy); the paper's, the modes.
  const auto phase = plan.study.find("tested_phase");
  std::string out =
      phase == plan.study.end()
          ? fmt::format("Power of the paper's analysis (α = {}, {} replicates, seed {}): the probability "
                        "that it finds the mode effect,\nwith its exact 95 % interval, the mean partial η² of "
                        "mode, and each Tukey pair's power.\n",
                        plan.alpha, plan.replicates, plan.seed)
          : fmt::format("Power of the design's analysis of its {} trials (α = {}, {} replicates, seed {}): the "
                        "probability that it finds\nthe effect of {}, with its exact 95 % interval, the mean partial "
                        "η², and each Tukey pair's power; subjects per group.\n",
                        phase->get<std::string>(), plan.alpha, plan.replicates, plan.seed,
                        fmt::join(plan.modes, " / "));
  out += fmt::format("{:>8}  {:<10}  {:>6}  {:<15}  {:>6}", "subjects", "metric", "power", "95 % CI", "η²");
  for (const auto& p : plan.pairs()) out += fmt::format("  {:>15}", p);
  out += "\n";
  for (const auto& r : table.rows) {
    out += fmt::format("{:>8}  {:<10}  {:>6.3f}  [{:.3f}, {:.3f}]  {:>6.3f}", r.subjects, r.metric, r.power.estimate,
                       r.power.lower, r.power.upper, r.mean_partial_eta_sq);
    for (const auto& p : r.pairs) out += fmt::format("  {:>15.3f}", p.power.estimate);
    out += "\n";
  }
  return out;
}

void writePowerPage(const PowerTable& table, const std::filesystem::path& file) {
  using detail::escape;
  const PowerPlan& plan = table.plan;
  std::string body;
  // Power curves: one figure per metric, the mode effect and each pair, the interval dashed.
  static constexpr std::array<const char*, 4> kColours{"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};
  for (const char* metric : kPowerMetrics) {
    detail::SvgPlot plot(fmt::format("Power to detect the mode effect: {}", metric), "subjects", "power (fraction of studies)");
    detail::Series power{"mode effect (ANOVA)", kColours[0], {}, 2.0, false, true, {}};
    detail::Series lower{"95 % interval", kColours[0], {}, 1.0, true, false, {}};
    detail::Series upper{"", kColours[0], {}, 1.0, true, false, {}};
    std::vector<detail::Series> pairs;
    for (const auto& p : plan.pairs()) {
      pairs.push_back({"Tukey " + p, kColours[1 + pairs.size() % 3], {}, 1.2, false, true, {}});
    }
    for (const auto& r : table.rows) {
      if (r.metric != metric) continue;
      power.points.emplace_back(r.subjects, r.power.estimate);
      lower.points.emplace_back(r.subjects, r.power.lower);
      upper.points.emplace_back(r.subjects, r.power.upper);
      for (std::size_t k = 0; k < r.pairs.size(); ++k) pairs[k].points.emplace_back(r.subjects, r.pairs[k].power.estimate);
    }
    plot.integerX();
    plot.yRange(0.0, 1.0);
    plot.add(std::move(power));
    plot.add(std::move(lower));
    plot.add(std::move(upper));
    for (auto& s : pairs) plot.add(std::move(s));
    body += fmt::format("<figure>{}<figcaption>{}: the fraction of {} simulated studies whose mode effect has p &lt; "
                        "{}, with its exact 95 % interval (dashed), and each Tukey pair's.</figcaption></figure>\n",
                        plot.svg(), escape(metric), plan.replicates, plan.alpha);
  }
  // The table.
  std::string rows;
  for (const auto& r : table.rows) {
    rows += fmt::format("<tr><td>{}</td><td>{}</td><td>{:.3f}</td><td>[{:.3f}, {:.3f}]</td><td>{:.3f}</td>", r.subjects,
                        escape(r.metric), r.power.estimate, r.power.lower, r.power.upper, r.mean_partial_eta_sq);
    for (const auto& p : r.pairs) rows += fmt::format("<td>{:.3f}</td>", p.power.estimate);
    rows += "</tr>\n";
  }
  std::string head = "<tr><th>subjects</th><th>metric</th><th>power</th><th>95 % CI</th><th>mean partial η²</th>";
  for (const auto& p : plan.pairs()) head += "<th>Tukey " + escape(p) + "</th>";
  head += "</tr>";
  const std::string html = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>hattr power analysis</title>\n"
      "<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}table{{border-collapse:collapse}}"
      "td,th{{border:1px solid #bbb;padding:.2em .5em;text-align:right}}figure{{margin:1em 0}}</style></head><body>\n"
      "<h1>Power analysis</h1>\n<p>{} simulated studies per design (seed {}, α = {}), study: {}. Power is the "
      "fraction of studies in which the paper's analysis (mode × subject ANOVA, subject random) finds the mode "
      "effect; the interval is Clopper–Pearson's.</p>\n<table>{}\n{}</table>\n{}</body></html>\n",
      plan.replicates, plan.seed, plan.alpha, escape(plan.study.value("name", std::string("?"))), head, rows, body);
  hattr::writeFileAtomically(file, html, hattr::Overwrite::kReplace);
}

}  // namespace hattr::report
