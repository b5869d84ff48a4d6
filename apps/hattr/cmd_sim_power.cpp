// hattr sim power [merge]: a power analysis by simulation, on one process, on MPI ranks
// (mpirun -n N hattr sim power ...) or in shards merged later (--shard i/N, then merge).

#include <chrono>
#include <exception>
#include <optional>
#include <iostream>
#include <span>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/atomic_file.hpp"
#include "hattr/ops/power_run.hpp"
#include "hattr/report/power.hpp"
#include "hattr/sim/power.hpp"
#include "mpi_world.hpp"

namespace hattr::cli {
namespace {

struct PowerCliOptions {
  std::string study;
  std::string subjects = "6,10,20,40";
  std::string phase;
  int replicates = 200;
  std::uint64_t seed = 1;
  double alpha = 0.05;
  int trials = 11;
  std::string glyph = "na";
  std::string hypothesis;
  int threads = 0;
  std::string shard;
  std::string out;
  std::string html;
  std::string scratch;
  bool json = false;
  bool force = false;
};

struct MergeCliOptions {
  std::vector<std::string> files;
  std::string html;
  bool json = false;
  bool force = false;
};

/// The files this run writes, checked before anything runs: nothing recorded is lost.
void checkOutputs(const PowerCliOptions& opt) {
  std::vector<std::filesystem::path> files;
  if (!opt.out.empty()) files.emplace_back(opt.out);
  if (!opt.html.empty()) files.emplace_back(opt.html);
  checkOutputFiles(files, opt.force);
}

/// The summary as asked: JSON or text, and the page.
void printTable(const report::PowerTable& table, const PowerCliOptions& opt, const nlohmann::json& run) {
  if (!opt.html.empty()) report::writePowerPage(table, opt.html);
  if (opt.json) {
    nlohmann::json j = report::powerTableToJson(table);
    if (!run.is_null()) j["run"] = run;
    return printJson(j);
  }
  std::cout << report::powerTableText(table);
  if (!run.is_null()) {
    std::cout << fmt::format("{} studies in {:.1f} s on {} process{} ({:.3f} studies per second)\n",
                             run["studies"].get<int>(), run["seconds"].get<double>(), run["processes"].get<int>(),
                             run["processes"].get<int>() == 1 ? "" : "es", run["studies_per_second"].get<double>());
  }
  if (!opt.html.empty()) std::cout << "page: " << opt.html << "\n";
}

/// This process's replicates (ops::runPowerPart), drawing progress on rank 0.
std::vector<report::ReplicateOutcome> runMine(const sim::PowerStudy& study, int part, int parts, bool draw) {
  const int count = std::max(0, (study.plan().replicates - part + parts - 1) / parts);
  Progress progress("power", draw ? static_cast<double>(count) : 0.0, "studies");
  std::vector<report::ReplicateOutcome> outcomes = ops::runPowerPart(study, part, parts, [&](double done, int of) {
    if (draw) progress.update(done, fmt::format("power: {} studies", of));
  });
  progress.finish();
  return outcomes;
}

void runPower(const PowerCliOptions& opt) {
  MpiWorld world;
  // Set-up: every rank checks the same input and prepares the study. When one fails, the
  // first that failed says why, and every rank ends with its code: none is left waiting.
  std::optional<sim::PowerStudy> study;
  std::pair<int, int> shard{0, 1};
  int threads = 1;
  std::exception_ptr failure;
  try {
    shard = shardOf(opt.shard);
    HATTR_THROW_UNLESS(world.size() == 1 || opt.shard.empty(),
                       "--shard: a run under mpirun splits its replicates across its ranks: give --shard or mpirun -n, "
                       "not both");
    HATTR_THROW_UNLESS(opt.shard.empty() || !opt.out.empty(), "--shard: expected --out FILE for the shard's replicates");
    HATTR_THROW_UNLESS(opt.shard.empty() || (opt.html.empty() && !opt.json),
                       "--shard: a shard has no table yet: give --html and --json to `hattr sim power merge`");
    if (world.rank() == 0) checkOutputs(opt);  // rank 0 writes them
    threads = threadsPerProcess(opt.threads, world);
    const std::string scratch_part = world.size() > 1 ? fmt::format("rank-{}", world.rank())
                                                      : fmt::format("shard-{}-of-{}", shard.first, shard.second);
    study.emplace(sim::PowerOptions{
        .study = opt.study, .glyph = opt.glyph, .training_trials = opt.trials, .recall_trials = opt.trials,
        .subject_counts = commaSeparatedInts(opt.subjects, "--subjects"), .replicates = opt.replicates, .seed = opt.seed,
        .alpha = opt.alpha, .threads = threads, .phase = opt.phase, .hypothesis = opt.hypothesis,
        .scratch = opt.scratch.empty() ? std::filesystem::path() : std::filesystem::path(opt.scratch) / scratch_part});
  } catch (...) {
    failure = std::current_exception();
  }
  endIfAnyRankFailed(world, failure);

  // The run: replicate r on rank r mod size (or in shard r mod N). A rank that fails now
  // ends every rank (the others would wait for it in the gather).
  try {
    const auto started = std::chrono::steady_clock::now();
    const int part = world.size() > 1 ? world.rank() : shard.first;
    const int parts = world.size() > 1 ? world.size() : shard.second;
    std::vector<report::ReplicateOutcome> outcomes = runMine(*study, part, parts, world.rank() == 0);
    const report::PowerPlan& plan = study->plan();
    if (!opt.shard.empty()) {
      hattr::writeFileAtomically(opt.out, report::powerShardToJson(plan, shard.first, shard.second, outcomes).dump(1) + "\n",
                              opt.force ? hattr::Overwrite::kReplace : hattr::Overwrite::kRefuse);
      std::cout << fmt::format("shard {}/{}: {} studies -> {} (merge the shards: hattr sim power merge FILES)\n",
                               shard.first, shard.second, outcomes.size(), opt.out);
      return;
    }
    // Gather the ranks' replicates, exactly, to rank 0.
    std::vector<double> flat;
    for (const auto& o : outcomes) report::encodeOutcome(o, flat);
    const std::vector<double> all = world.gatherToRoot(flat);
    if (world.rank() != 0) return;
    const std::size_t size = report::encodedOutcomeSize(plan);
    outcomes.clear();
    for (std::size_t at = 0; at < all.size(); at += size) {
      outcomes.push_back(report::decodeOutcome(plan, std::span<const double>(all).subspan(at, size)));
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    if (!opt.out.empty()) {
      hattr::writeFileAtomically(opt.out, report::powerShardToJson(plan, 0, 1, outcomes).dump(1) + "\n",
                              opt.force ? hattr::Overwrite::kReplace : hattr::Overwrite::kRefuse);
    }
    const report::PowerTable table = report::summarizePower(plan, std::move(outcomes));
    printTable(table, opt, ops::powerRunJson(plan.replicates, seconds, world.size(), threads));
  } catch (...) {
    if (world.size() == 1) throw;
    printFailure(std::current_exception(), world);
    study.reset();  // its scratch folder, which the abort would leave
    world.abort(exitCodeOf(std::current_exception()));
  }
}

void runMerge(const MergeCliOptions& opt) {
  if (!opt.html.empty()) checkOutputFiles({opt.html}, opt.force);
  const std::vector<std::filesystem::path> files(opt.files.begin(), opt.files.end());
  const report::PowerTable table = report::mergePowerShards(files);
  PowerCliOptions print;
  print.html = opt.html;
  print.json = opt.json;
  printTable(table, print, nullptr);
}

}  // namespace

void registerPowerCommands(CLI::App& sim) {
  auto opt = std::make_shared<PowerCliOptions>();
  auto* power = sim.add_subcommand(
      "power", "Power analysis: for each number of subjects, how often the paper's analysis finds the mode effect "
               "(run it under mpirun -n N to use N processes)");
  auto* study = power->add_option("--study", opt->study,
                                  "A study file with simulated subjects (default: the paper's study in silico)");
  power->add_option("--subjects", opt->subjects, "The designs: numbers of subjects (per group in a study of groups), "
                    "comma-separated")->capture_default_str();
  power->add_option("--phase", opt->phase, "A study of groups and sessions: the phase compared (default: its retention, "
                    "else post-test, else recall, else its last phase)");
  power->add_option("--replicates", opt->replicates, "Simulated studies per design")->capture_default_str();
  power->add_option("--seed", opt->seed, "Replicate r is the study with seed + r")->capture_default_str();
  power->add_option("--alpha", opt->alpha, "Significance level")->capture_default_str();
  power->add_option("--trials", opt->trials, "Training and recall trials per mode (the paper's study only)")
      ->check(CLI::Range(2, 50))
      ->capture_default_str()
      ->excludes(study);
  power->add_option("--glyph", opt->glyph, "The glyph: a file, a built-in name (hattr sim glyphs) or the character (the paper's study only)")
      ->capture_default_str()
      ->excludes(study);
  power->add_option("--hypothesis", opt->hypothesis,
                    "Learning hypothesis of every subject: position-plan, force-plan, guidance-dependent (default: the "
                    "study's; the paper's study: position-plan)");
  power->add_option("--threads", opt->threads, "Subjects simulated at once per process (0: this machine's cores "
                                               "shared by its ranks)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  power->add_option("--shard", opt->shard, "Run only replicates r with r mod N = i (i/N), into --out, for schedulers "
                                           "without MPI (Slurm job arrays); merge them with `hattr sim power merge`");
  power->add_option("--out", opt->out, "Write the replicates' outcomes (exact) to this file: a shard, or the whole run");
  power->add_option("--html", opt->html, "Write a page with the table and the power curves");
  power->add_option("--scratch", opt->scratch, "Folder for the replicates' databases (default: a temporary folder)");
  power->add_flag("--json", opt->json, "Print JSON: plan, rows [{subjects, metric, mode_effect {power, ci95}, "
                                       "mean_partial_eta_sq, tukey}], run");
  power->add_flag("--force", opt->force, "Replace existing output files");

  auto merge_opt = std::make_shared<MergeCliOptions>();
  auto* merge = power->add_subcommand("merge", "Merge shard files (hattr sim power --shard i/N --out FILE) into the table");
  merge->add_option("files", merge_opt->files, "Shard files")->required();
  merge->add_option("--html", merge_opt->html, "Write a page with the table and the power curves");
  merge->add_flag("--json", merge_opt->json, "Print JSON, as hattr sim power --json (without run)");
  merge->add_flag("--force", merge_opt->force, "Replace an existing page");
  merge->callback([merge_opt] { runMerge(*merge_opt); });
  power->callback([opt, power, merge] {
    if (!power->got_subcommand(merge)) runPower(*opt);
  });
}

}  // namespace hattr::cli
