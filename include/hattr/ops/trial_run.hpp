#pragma once
/// One scripted trial as one library call (`hattr record`, `hattr train`, Python's
/// `run_trial`): the device opened on the world, the reference and the hand script checked
/// against what the device can render (when training), the trial run through the whole
/// pipeline, and what disturbed it. Writing the recording stays with the caller (the CLI keeps
/// a recording it cannot write; Python returns it).
///
/// Threads: blocks until the trial ends (simulated time: as fast as it runs).

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::ops {

struct ScriptedTrialRun {
  std::string device = "sim://pen";    ///< a device URI (`hattr devices`)
  render::WorldConfig world;           ///< the paper
  HapticProfile hand;                  ///< the script the simulated hand writes
  /// The expert's profile to train against; none: record (options.expert is set from it).
  std::optional<HapticProfile> reference;
  /// Rate, clock, tail, end rule, metadata and, when training, the strategy and its settings;
  /// its hand_label and reference_label name the files in the metadata and in messages.
  session::ScriptedTrialOptions options;
  /// How messages name the two profiles: "--hand FILE" in the CLI, "hand FILE" in Python.
  std::string hand_what = "hand";
  std::string reference_what = "reference";
};

struct ScriptedTrialResult {
  session::TrialResult trial;
  std::string disturbed;               ///< session::disturbanceOf(trial): "" when clean
  std::string mode;                    ///< the strategy's name, "expert" for a recording
  /// The CLI's --json: the profile's summary (profileSummaryJson), clamps, missed_samples,
  /// overruns, faults, link_faults, stalls, clock, end_reason, physical_events, disturbed.
  [[nodiscard]] nlohmann::json toJson() const;
};

/// Runs the trial. Throws InputError for bad settings or a reference or hand script the device
/// cannot render (with the remedy); a trial the device broke off returns with
/// trial.failure set and what it recorded.
ScriptedTrialResult runScriptedTrial(ScriptedTrialRun run);

}  // namespace hattr::ops
