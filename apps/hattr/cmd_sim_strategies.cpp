// hattr sim compare-strategies: one design under each training strategy and learning hypothesis,
// its phases' outcomes side by side, with an A/A check (docs/simulation.md, "Comparing strategies").

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/sim/strategy_comparison.hpp"

namespace hattr::cli {
namespace {

struct StrategiesOptions {
  std::string strategies;  // empty: every strategy that is not mentored
  std::string hypotheses = "position-plan,force-plan,guidance-dependent";
  std::string design = "groups-retention";
  std::string study;
  int subjects = 6;
  int trials = 0;
  std::uint64_t seed = 1;
  int aa_seeds = 3;
  int threads = 0;
  bool json = false;
};

/// "a,b,c" as its items, each once.
std::vector<std::string> commaList(const std::string& text, const char* option) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    HATTR_THROW_UNLESS(!item.empty(), "{}: expected comma-separated names, got \"{}\"", option, text);
    HATTR_THROW_UNLESS(std::find(out.begin(), out.end(), item) == out.end(), "{}: \"{}\" is given twice", option, item);
    out.push_back(item);
  }
  HATTR_THROW_UNLESS(!out.empty(), "{}: expected at least one name, got \"{}\"", option, text);
  return out;
}

/// "12.3 ±1.4" (no interval below two subjects).
std::string meanText(const report::SubjectMean& m) {
  if (!std::isfinite(m.mean)) return "-";
  return std::isfinite(m.ci) ? fmt::format("{:.1f} ±{:.1f}", m.mean, m.ci) : fmt::format("{:.1f}", m.mean);
}

/// Per hypothesis and metric: a row per phase, a column per strategy, then p and the A/A count.
void printTable(const sim::StrategyComparison& c) {
  std::cout << fmt::format("Strategies compared on the design {} ({} simulated subjects per strategy, seed {}): each "
                           "strategy's mean DTW cost over its subjects (±95 % interval), lower is closer to the "
                           "expert; p: one-way ANOVA between the strategies; A/A: studies of {} with every force off "
                           "that found p < 0.05.\n",
                           c.design, c.subjects, c.seed, c.aa_seeds);
  std::size_t phase_width = 5;
  for (const auto& h : c.hypotheses) {
    for (const auto& p : h.phases) phase_width = std::max(phase_width, p.phase.size() + p.skill.size() + 3);
  }
  std::vector<std::size_t> widths;
  for (const auto m : c.strategies) widths.push_back(std::max<std::size_t>(13, guidance::strategyName(m).size()));
  for (const auto& h : c.hypotheses) {
    for (const bool shape : {true, false}) {
      std::string header = fmt::format("\n{}, {} cost\n{:<{}}", sim::hypothesisName(h.hypothesis),
                                       shape ? "shape" : "force", "phase", phase_width);
      for (std::size_t i = 0; i < c.strategies.size(); ++i) {
        header += fmt::format(" {:>{}}", guidance::strategyName(c.strategies[i]), widths[i]);
      }
      std::cout << header << fmt::format(" {:>8} {:>4}\n", "p", "A/A");
      for (const auto& p : h.phases) {
        std::string row = fmt::format("{:<{}}", fmt::format("{} ({})", p.phase, p.skill), phase_width);
        const auto& means = shape ? p.shape : p.force;
        for (std::size_t i = 0; i < means.size(); ++i) row += fmt::format(" {:>{}}", meanText(means[i]), widths[i]);
        const double pv = shape ? p.p_shape : p.p_force;
        row += fmt::format(" {:>8} {:>4}\n", std::isfinite(pv) ? fmt::format("{:.3g}", pv) : "-",
                           shape ? p.aa_significant_shape : p.aa_significant_force);
        std::cout << row;
      }
    }
  }
}

void runStrategies(const StrategiesOptions& o) {
  sim::StrategyComparisonOptions options{.study = o.study, .design = o.design, .subjects = o.subjects,
                                         .max_trials = o.trials, .seed = o.seed, .aa_seeds = o.aa_seeds,
                                         .threads = o.threads};
  if (!o.strategies.empty()) {
    for (const auto& name : commaList(o.strategies, "--strategies")) options.strategies.push_back(guidance::parseMode(name));
  }
  for (const auto& name : commaList(o.hypotheses, "--hypotheses")) {
    options.hypotheses.push_back(sim::parseHypothesis(name, "--hypotheses"));
  }
  const int studies = static_cast<int>(options.hypotheses.size()) * (1 + o.aa_seeds);
  Progress progress("strategies", studies, "studies");
  options.progress = [&progress](int done, int, std::string_view what) { progress.update(done, std::string(what)); };
  const sim::StrategyComparison comparison = sim::compareStrategies(options);
  progress.finish();
  if (o.json) return printJson(sim::strategyComparisonToJson(comparison));
  printTable(comparison);
}

}  // namespace

void registerStrategyComparisonCommand(CLI::App& sim) {
  auto o = std::make_shared<StrategiesOptions>();
  auto* cmd = sim.add_subcommand("compare-strategies",
                                 "Run one design under each training strategy (a group each) and learning hypothesis: "
                                 "each phase's outcome per strategy, with an A/A check");
  cmd->add_option("--strategies", o->strategies, "Comma-separated strategies (`hattr strategies`, none mentored); "
                  "default: every one that is not mentored");
  cmd->add_option("--hypotheses", o->hypotheses, "Comma-separated: position-plan, force-plan, guidance-dependent")
      ->capture_default_str();
  cmd->add_option("--design", o->design, "A shipped design with sessions (`hattr study example --list`)")
      ->capture_default_str();
  cmd->add_option("--study", o->study, "A study file of groups and sessions instead (its groups replaced by one per "
                  "strategy, its subjects by simulated ones)");
  cmd->add_option("--subjects", o->subjects, "Simulated subjects per strategy")->check(CLI::Range(2, 100))
      ->capture_default_str();
  cmd->add_option("--trials", o->trials, "Each block at most this many trials (0: as designed)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "The studies' seed; A/A study k uses seed + k")->capture_default_str();
  cmd->add_option("--aa-seeds", o->aa_seeds, "A/A studies per hypothesis (every force off)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  cmd->add_option("--threads", o->threads, "Subjects simulated at once (0: this machine's cores)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print JSON: {design, subjects, seed, aa_seeds, alpha, strategies, hypotheses "
                                   "[{hypothesis, phases [{phase, skill, p_shape, p_force, aa {significant_shape, "
                                   "significant_force}, strategies [{strategy, shape {subjects, mean, ci}, force}]}]}]}");
  cmd->callback([o] { runStrategies(*o); });
}

}  // namespace hattr::cli
