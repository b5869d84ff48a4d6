// hattr sim plan: the smallest design that reaches a target power, by simulation, on one
// process, on MPI ranks (mpirun -n N hattr sim plan ...) or in shards on one state folder.

#include <exception>
#include <cmath>
#include <iostream>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/ops/plan_run.hpp"
#include "hattr/report/plan.hpp"
#include "hattr/sim/plan.hpp"
#include "hattr/sim/trainee_model.hpp"
#include "mpi_world.hpp"

namespace hattr::cli {
namespace {

struct PlanCliOptions {
  std::vector<std::string> studies;
  std::string glyph = "na";
  std::string trials = "11";
  std::string calibration;
  double effect_size = 0.0;
  std::string compare = "mode";
  std::string outcome = "shape";
  std::string analysis = "anova";
  std::string phase;
  std::string hypotheses;
  report::PlanSearchOptions search;
  double alpha = 0.05;
  double max_hours_per_subject = 0.0;  ///< 0: no limit
  double max_lab_hours = 0.0;          ///< 0: no limit
  double session_setup_min = 10.0;
  std::uint64_t seed = 1;
  int threads = 0;
  std::string state;
  std::string shard;
  double shard_wait_min = 60.0;
  std::string html;
  bool json = false;
  bool force = false;
  bool quiet = false;
};

/// The hypotheses asked: a comma-separated list, "each" for every one, or none (the study's).
std::vector<std::string> hypothesesOf(const std::string& text) {
  if (text.empty()) return {""};
  std::vector<std::string> names;
  if (text == "each") {
    for (const auto h : sim::allHypotheses()) names.emplace_back(sim::hypothesisName(h));
    return names;
  }
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    names.emplace_back(sim::hypothesisName(sim::parseHypothesis(item, "--hypothesis")));
  }
  HATTR_THROW_UNLESS(!names.empty(), "--hypothesis: expected names or \"each\", got \"{}\"", text);
  return names;
}

/// The searches: the calibration design, or each study (the paper's at each trial count) under
/// each hypothesis.
std::vector<ops::PlanSearchSpec> searchesOf(const PlanCliOptions& opt, int threads) {
  std::vector<ops::PlanSearchSpec> searches;
  if (!opt.calibration.empty()) {
    HATTR_THROW_UNLESS(opt.calibration == "two-sample" || opt.calibration == "paired",
                       "--calibration: expected two-sample or paired, got \"{}\"", opt.calibration);
    HATTR_THROW_UNLESS(opt.compare == "mode", "--compare {}: the calibration design has two conditions: expected "
                       "mode (their difference)", opt.compare);
    searches.push_back({sim::makeCalibrationDesign({.paired = opt.calibration == "paired",
                                                    .effect_size = opt.effect_size, .seed = opt.seed}),
                        ""});
    return searches;
  }
  const std::vector<int> trials = commaSeparatedInts(opt.trials, "--trials");
  for (const int t : trials) {
    HATTR_THROW_UNLESS(t >= 2 && t <= 50, "--trials: expected 2 to 50 trials per mode, got {}", t);
  }
  for (const std::string& hypothesis : hypothesesOf(opt.hypotheses)) {
    const auto add = [&](const std::string& study, int t) {
      sim::StudyPlanOptions o;
      o.power = {.study = study, .glyph = opt.glyph, .training_trials = t, .recall_trials = t, .seed = opt.seed,
                 .alpha = opt.alpha, .threads = threads, .phase = opt.phase, .hypothesis = hypothesis};
      o.max_subjects = opt.search.max_subjects;
      o.max_replicates = opt.search.max_replicates;
      o.comparison = opt.compare;
      o.outcome = opt.outcome;
      o.analysis = sim::parsePlanAnalysis(opt.analysis, "--analysis");
      o.session_setup_s = opt.session_setup_min * 60.0;
      searches.push_back({sim::makeStudyPlanDesign(o), hypothesis});
    };
    if (opt.studies.empty()) {
      for (const int t : trials) add("", t);
    } else {
      for (const auto& study : opt.studies) add(study, 0);
    }
  }
  return searches;
}

/// The analysis each design's replicates run, in words.
std::string analysisWords(const PlanCliOptions& opt) {
  if (opt.calibration == "two-sample") return "one-way ANOVA of two groups (the two-sample t-test)";
  if (opt.calibration == "paired") return "mode × subject ANOVA, one value per cell (the paired t-test)";
  if (opt.analysis == "mixed") {
    return "the design report's linear mixed model: outcome ~ condition + (1 | subject), + (1 | subject:condition) "
           "where subjects repeat conditions; Satterthwaite's F, or for a pair its t with Tukey's adjustment";
  }
  return "ANOVA as `hattr sim power`: mode × subject with subject random, or between groups one-way of the "
         "subjects' means; Tukey HSD for a pair";
}

void printPlan(const ops::PlanRunResult& result, const PlanCliOptions& opt, const MpiWorld& world, int threads) {
  if (!opt.html.empty()) report::writePlanPage(result.report, opt.html);
  if (opt.json) {
    nlohmann::json j = report::planReportToJson(result.report);
    j["run"] = {{"seconds", result.seconds}, {"replicates_run", result.replicates_run},
                {"processes", world.size()}, {"threads_per_process", threads}};
    return printJson(j);
  }
  std::cout << report::planReportText(result.report);
  std::cout << fmt::format("{} studies run now in {:.1f} s{}\n", result.replicates_run, result.seconds,
                           world.size() > 1 ? fmt::format(" by this rank of {}", world.size()) : std::string());
  if (!opt.html.empty()) std::cout << "page: " << opt.html << "\n";
}

void runPlanCommand(PlanCliOptions opt) {
  MpiWorld world;
  // Set-up on every rank; when one fails, the first that failed says why (as sim power).
  std::vector<ops::PlanSearchSpec> searches;
  ops::PlanRunOptions run;
  int threads = 1;
  std::exception_ptr failure;
  try {
    const auto [part, parts] = shardOf(opt.shard);
    HATTR_THROW_UNLESS(world.size() == 1 || opt.shard.empty(),
                       "--shard: a run under mpirun splits its replicates across its ranks: give --shard or mpirun -n, "
                       "not both");
    HATTR_THROW_UNLESS(opt.shard.empty() || !opt.state.empty(),
                       "--shard: shards share their replicates through a folder: expected --state DIR (the same for "
                       "every shard)");
    HATTR_THROW_UNLESS(opt.calibration.empty() || (opt.studies.empty() && opt.hypotheses.empty() && opt.phase.empty()),
                       "--calibration: the built-in calibration design has no study, hypothesis or phase");
    HATTR_THROW_UNLESS(opt.calibration.empty() || (opt.outcome == "shape" && opt.analysis == "anova"),
                       "--calibration: the calibration design's outcome is its normal value, analyzed by the t-test's "
                       "ANOVA: expected no --outcome or --analysis, got --outcome {} --analysis {}", opt.outcome,
                       opt.analysis);
    HATTR_THROW_UNLESS(!opt.calibration.empty() || opt.effect_size == 0.0,
                       "--effect-size: only for --calibration (a study's effect comes from its simulated subjects)");
    HATTR_THROW_UNLESS(opt.max_hours_per_subject >= 0.0 && opt.max_lab_hours >= 0.0 && opt.session_setup_min >= 0.0,
                       "--max-hours-per-subject, --max-lab-hours, --session-setup: expected 0 (no limit) or more");
    opt.search.check();
    HATTR_THROW_UNLESS(!opt.calibration.empty() || opt.search.min_subjects >= 3,
                       "--min-subjects: a study's design needs at least 3 subjects (Tukey's test), got {}",
                       opt.search.min_subjects);
    HATTR_THROW_UNLESS(!opt.calibration.empty() || opt.search.max_replicates <= 1'000'000,
                       "--max-replicates: a study's plan runs at most 1000000 per design, got {}",
                       opt.search.max_replicates);
    if (world.rank() == 0 && !opt.html.empty()) checkOutputFiles({opt.html}, opt.force);
    threads = threadsPerProcess(opt.threads, world);
    searches = searchesOf(opt, threads);
    run.search = opt.search;
    run.alpha = opt.alpha;
    run.comparison = opt.calibration.empty() ? opt.compare : "the difference between the two conditions";
    run.outcome = opt.calibration.empty() ? opt.outcome : "the normal outcome";
    run.analysis = analysisWords(opt);
    if (opt.max_hours_per_subject > 0.0) run.max_hours_per_subject = opt.max_hours_per_subject;
    if (opt.max_lab_hours > 0.0) run.max_lab_hours = opt.max_lab_hours;
    run.extra = {{"session_setup_min", opt.session_setup_min}};
    run.state = opt.state;
    HATTR_THROW_UNLESS(opt.shard_wait_min > 0.0 && std::isfinite(opt.shard_wait_min),
                       "--shard-wait: expected minutes above 0, got {}", opt.shard_wait_min);
    run.shard_wait_s = opt.shard_wait_min * 60.0;
    run.part = world.size() > 1 ? world.rank() : part;
    run.parts = world.size() > 1 ? world.size() : parts;
    if (world.size() > 1) run.exchange = [&world](const std::vector<double>& mine) { return world.gatherToAll(mine); };
    run.writes_state = world.rank() == 0;
    if (!opt.quiet && world.rank() == 0) run.log = [](const std::string& line) { std::cerr << line << "\n"; };
  } catch (...) {
    failure = std::current_exception();
  }
  endIfAnyRankFailed(world, failure);
  try {
    const ops::PlanRunResult result = ops::runPlan(searches, run);
    if (world.rank() == 0) printPlan(result, opt, world, threads);
  } catch (...) {
    if (world.size() == 1) throw;
    printFailure(std::current_exception(), world);
    searches.clear();  // their scratch folders, which the abort would leave
    world.abort(exitCodeOf(std::current_exception()));
  }
}

}  // namespace

void registerPlanCommand(CLI::App& sim) {
  auto opt = std::make_shared<PlanCliOptions>();
  auto* plan = sim.add_subcommand(
      "plan", "Plan a study: the smallest design whose analysis finds the comparison with the target power, by "
              "simulation (run it under mpirun -n N to use N processes)");
  auto* study = plan->add_option("--study", opt->studies, "A study file with simulated subjects; give several to "
                                 "compare designs (groups against within-subjects, sessions). Default: the paper's study");
  auto* glyph = plan->add_option("--glyph", opt->glyph, "The glyph of the paper's study")->capture_default_str()->excludes(study);
  auto* trials = plan->add_option("--trials", opt->trials, "Training and recall trials per mode of the paper's study; "
                                  "several (comma-separated) are searched each")->capture_default_str()->excludes(study);
  auto* calibration = plan->add_option("--calibration", opt->calibration,
                                       "The built-in calibration design: two-sample or paired (a normal outcome whose "
                                       "analysis is a t-test)")->excludes(study)->excludes(glyph)->excludes(trials);
  plan->add_option("--effect-size", opt->effect_size, "The calibration design's Cohen's d")->needs(calibration);
  plan->add_option("--compare", opt->compare, "What is compared: mode (the effect of the modes or groups) or two of "
                   "them, e.g. ALPHA-PCONTROL (Tukey-adjusted)")->capture_default_str();
  plan->add_option("--outcome", opt->outcome, "shape (the trajectory's DTW cost), force (the haptic profile's) or a "
                   "kinematic measure of each trial (mean_speed_m_per_s, normalized_jerk, ...: hattr kinematics --json)")
      ->capture_default_str();
  plan->add_option("--analysis", opt->analysis, "anova (sim power's) or mixed (the design report's linear mixed "
                   "model)")->capture_default_str();
  plan->add_option("--phase", opt->phase, "A design of groups and sessions: the phase compared (retention, transfer, "
                   "...; default as sim power)");
  plan->add_option("--hypothesis", opt->hypotheses, "Learning hypotheses, comma-separated, or each (default: the "
                   "study's; the paper's study: position-plan)");
  plan->add_option("--power", opt->search.target, "The target power")->capture_default_str();
  plan->add_option("--alpha", opt->alpha, "Significance level")->capture_default_str();
  plan->add_option("--min-subjects", opt->search.min_subjects, "The smallest design (per group)")->capture_default_str();
  plan->add_option("--max-subjects", opt->search.max_subjects, "The largest design (per group)")->capture_default_str();
  plan->add_option("--step", opt->search.step, "Designs in steps of this many subjects (6: every Williams order "
                   "as often)")->capture_default_str();
  plan->add_option("--batch", opt->search.batch, "Replicates a design gets at each look")->capture_default_str();
  plan->add_option("--max-replicates", opt->search.max_replicates, "A design's most replicates")->capture_default_str();
  plan->add_option("--confidence", opt->search.confidence, "Each design's decision's confidence, over its looks")
      ->capture_default_str();
  plan->add_option("--max-hours-per-subject", opt->max_hours_per_subject,
                   "The most lab hours one subject may take (0: no limit)")->capture_default_str();
  plan->add_option("--max-lab-hours", opt->max_lab_hours, "The most lab hours of all subjects (0: no limit)")
      ->capture_default_str();
  plan->add_option("--session-setup", opt->session_setup_min, "A session's lab minutes besides its trials")
      ->capture_default_str();
  plan->add_option("--seed", opt->seed, "Replicate r's subjects are seeded as sim power's with seed + r")
      ->capture_default_str();
  plan->add_option("--threads", opt->threads, "Subjects simulated at once per process (0: the cores shared by the "
                   "machine's ranks)")->check(CLI::Range(0, 256))->capture_default_str();
  plan->add_option("--state", opt->state, "Keep every replicate's outcome in this folder: a killed plan resumes from "
                   "it, shards share it");
  plan->add_option("--shard", opt->shard, "Run replicates r with r mod N = i (i/N) of each batch, the other shards "
                   "running at once on the same --state folder");
  plan->add_option("--shard-wait", opt->shard_wait_min, "A shard's longest wait for the other shards' replicates "
                   "of a batch [min]")->capture_default_str();
  plan->add_option("--html", opt->html, "Write a page with the power curves and the answer");
  plan->add_flag("--json", opt->json, "Print JSON: plan, searches [{label, points, answer, sentence}], answers, run");
  plan->add_flag("--force", opt->force, "Replace an existing page");
  plan->add_flag("--quiet", opt->quiet, "No line per batch on stderr");
  plan->callback([opt] { runPlanCommand(*opt); });
}

}  // namespace hattr::cli
