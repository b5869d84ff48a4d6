// hattr record | train: one trial through the whole pipeline, written as a haptic profile.

#include <iostream>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "cli_common.hpp"
#include "hattr/library/profile_template.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/ops/trial_run.hpp"

namespace hattr::cli {
namespace {

struct TrialOptions {
  std::string device = "sim://pen";
  std::string hand;
  std::string output;
  std::string world;
  double rate_hz = 1000.0;
  std::string clock = "sim";
  std::string subject;
  std::string skill;
  double tail_s = 0.3;
  double pen_up_end_s = 0.0;
  double max_duration_s = 0.0;
  bool force = false;
  bool json = false;
  bool keep_disturbed = false;
  // train only
  std::string mode = "basic";
  std::vector<std::string> params;
  std::uint64_t seed = 1;
  std::string reference;
  std::string indexing = "time";
  double speed = 1.0;
  int trial = 0;
};

void addCommonOptions(CLI::App& cmd, TrialOptions& opt) {
  cmd.add_option("--device", opt.device, "Device URI (see `hattr devices`)")->capture_default_str();
  cmd.add_option("--hand", opt.hand, "Hand script: a profile the simulated hand writes (position, force, pen-down)")
      ->required();
  cmd.add_option("-o,--output", opt.output, "Haptic-profile CSV to write")->required();
  cmd.add_option("--world", opt.world, "World (paper) configuration JSON (default: built-in defaults)");
  cmd.add_option("--rate", opt.rate_hz, "Servo rate [Hz]")->check(CLI::Range(1.0, 10000.0))->capture_default_str();
  cmd.add_option("--clock", opt.clock,
                 "sim: simulated time (fast, deterministic); real: the real-time loop. Devices that cannot be "
                 "simulated (udp://, hardware plugins) always run in real time")
      ->check(CLI::IsMember({"sim", "real"}))
      ->capture_default_str();
  cmd.add_option("--subject", opt.subject, "Subject recorded in the metadata");
  cmd.add_option("--skill", opt.skill, "Skill or character recorded in the metadata");
  cmd.add_option("--tail", opt.tail_s, "Keep recording this long after the script ends [s]")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  cmd.add_option("--pen-up-end", opt.pen_up_end_s,
                 "End the trial once the pen has been up this long after writing began [s] (0: the script's "
                 "length plus --tail, as before)")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  cmd.add_option("--max-duration", opt.max_duration_s,
                 "With --pen-up-end: the longest the trial may last [s] (0: 3 x the script's length)")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  cmd.add_flag("--force", opt.force, "Replace the output file if it exists");
  cmd.add_flag("--json", opt.json,
               "Print a JSON summary: the profile summary plus clamps, the loop's counters, the physical events and "
               "the disturbance");
  cmd.add_flag("--keep-disturbed", opt.keep_disturbed,
               "Exit 0 for a disturbed trial too (stalls, missed samples, faults, lost links, the pen through the "
               "paper, the device at its force limit, the pen outside the workspace); it is written, marked, either "
               "way");
}

void runTrialCommand(const TrialOptions& opt, bool training) {
  checkOutputFiles({opt.output}, opt.force);  // before the trial: a recording is never left unwritable
  HapticProfile hand = io::readProfileCsv(opt.hand);  // the hand script first, then the world
  ops::ScriptedTrialRun run{.device = opt.device,
                            .world = worldConfigOrDefault(opt.world),
                            .hand = std::move(hand),
                            .reference = {},
                            .options = {.rate_hz = opt.rate_hz,
                                        .tail_s = opt.tail_s,
                                        .pen_up_end_s = opt.pen_up_end_s,
                                        .max_duration_s = opt.max_duration_s,
                                        .clock = session::parseClock(opt.clock),
                                        .subject = opt.subject,
                                        .skill = opt.skill,
                                        .hand_label = opt.hand},
                            .hand_what = "--hand",
                            .reference_what = "--reference"};
  if (training) {
    run.reference = library::readReference(opt.reference);
    run.options.reference_label = opt.reference;
    run.options.mode = guidance::parseMode(opt.mode);
    run.options.indexing = guidance::parseIndexing(opt.indexing);
    run.options.speed = opt.speed;
    run.options.trial = opt.trial;
    for (const auto& setting : opt.params) run.options.parameters.push_back(guidance::parseStrategySetting(setting));
    run.options.seed = opt.seed;
  }
  const ops::ScriptedTrialResult outcome = ops::runScriptedTrial(std::move(run));
  const session::TrialResult& result = outcome.trial;
  for (const auto& c : result.clamps) std::cerr << "hattr: clamped: " << c << '\n';
  // A trial the device broke off keeps what it recorded (marked failed) and exits 1.
  if (!result.failure.empty()) {
    if (result.profile.empty()) throw Error(fmt::format("the trial failed before recording began: {}", result.failure));
    writeRecording(result.profile, opt.output, opt.force);
    throw Error(fmt::format("the trial failed after {:.3f} s: {}; what was recorded is in {} (metadata: failed)",
                            result.profile.duration_s(), result.failure, opt.output));
  }
  writeRecording(result.profile, opt.output, opt.force);

  if (opt.json) {
    nlohmann::json json = outcome.toJson();
    json["file"] = opt.output;
    printJson(json);
  } else {
    std::cout << fmt::format("{} {} -> {}: {} samples, {:.3f} s, {} missed, {} overruns, {} stalls, {} faults, {} clock\n",
                             training ? "trained" : "recorded", outcome.mode, opt.output, result.profile.size(),
                             result.profile.duration_s(), result.missed_samples, result.overruns, result.stalls,
                             result.faults, result.clock);
  }
  // A disturbed trial is written, marked in its metadata (`disturbed`), and fails the command
  // unless it was asked to keep it.
  if (!outcome.disturbed.empty() && !opt.keep_disturbed) {
    throw Error(fmt::format("the trial was disturbed: {}; it is kept in {}, marked `disturbed` in its metadata "
                            "(--keep-disturbed exits 0 for it)",
                            outcome.disturbed, opt.output));
  }
}

/// `hattr strategies`: every training strategy, its plain name, what it does, its source and
/// its parameters.
void runStrategies(bool json) {
  if (json) return printJson({{"strategies", ops::strategiesJson()}});
  for (const auto& s : guidance::strategyCatalog()) {
    std::cout << fmt::format("{:<19} {} — {}\n", guidance::strategyName(s.mode), s.plain_name, s.description);
    for (const auto& p : s.parameters) {
      if (!p.choices.empty()) {
        std::cout << fmt::format("{:<19}   {} = {} ({}): {}\n", "", p.name,
                                 p.choices.at(static_cast<std::size_t>(p.default_value)), fmt::join(p.choices, " or "),
                                 p.meaning);
        continue;
      }
      const std::string_view unit = p.unit == "1" ? "" : p.unit;  // a ratio: no unit to show
      std::cout << fmt::format("{:<19}   {} = {}{}{} ({} to {}): {}\n", "", p.name, p.default_value, unit.empty() ? "" : " ",
                               unit, p.min, p.max, p.meaning);
    }
  }
}

}  // namespace

void registerRecordTrainCommands(CLI::App& app) {
  auto strategies_json = std::make_shared<bool>(false);
  auto* strategies = app.add_subcommand("strategies", "The training strategies: name, plain name, what each does, its "
                                                      "parameters with units, defaults and ranges (docs/training_modes.md)");
  strategies->add_flag("--json", *strategies_json, "Print JSON: strategies [{name, plain_name, description, source, "
                                                   "mentored, scheduled, parameters [{name, unit, default, min, max, "
                                                   "meaning} or {name, default, choices, meaning}]}]");
  strategies->callback([strategies_json] { runStrategies(*strategies_json); });

  auto record_opt = std::make_shared<TrialOptions>();
  auto* record = app.add_subcommand(
      "record", "Record a haptic profile while the (simulated) hand writes the script on the virtual paper");
  addCommonOptions(*record, *record_opt);
  record->callback([record_opt] { runTrialCommand(*record_opt, false); });

  auto train_opt = std::make_shared<TrialOptions>();
  auto* train = app.add_subcommand(
      "train", "One training trial against an expert's profile with a training strategy (`hattr strategies` lists "
               "them); the output holds the user's force and the guidance force separately");
  addCommonOptions(*train, *train_opt);
  train->add_option("--mode", train_opt->mode, "The strategy: basic (no assistance), pcontrol (position guidance), "
                    "alpha (force guidance), channel, error-augmentation, noise, playback, fading, assist-as-needed, "
                    "partial-then-full (`hattr strategies`)")
      ->capture_default_str();
  train->add_option("--param", train_opt->params, "A parameter of the strategy, KEY=VALUE in the units `hattr "
                    "strategies` gives, or a choice's name (repeatable), e.g. --param half_width_mm=1.5 --param base=alpha; "
                    "STRATEGY.KEY=VALUE sets another strategy's, such as a scheduled strategy's law's gains "
                    "(--param pcontrol.kp_N_per_mm=0.2); a scheduled strategy (fading, ...) plays its first trial's law "
                    "and gain");
  train->add_option("--seed", train_opt->seed, "Seed of the strategy's random force (noise)")->capture_default_str();
  train->add_option("--reference", train_opt->reference, "The expert's haptic profile: a CSV file, or a person's template, library:PATH#PERSON/SKILL")->required();
  train->add_option("--indexing", train_opt->indexing, "time (the paper's) or progress (follows the trainee along the path)")
      ->check(CLI::IsMember({"time", "progress"}))
      ->capture_default_str();
  train->add_option("--speed", train_opt->speed, "Reference playback speed (time indexing)")
      ->check(CLI::Range(0.05, 10.0))
      ->capture_default_str();
  train->add_option("--trial", train_opt->trial, "Trial number recorded in the metadata")->capture_default_str();
  train->callback([train_opt] { runTrialCommand(*train_opt, true); });
}

}  // namespace hattr::cli
