#include "hattr/ops/trial_run.hpp"

#include <fmt/format.h>

#include "hattr/device/hand.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/session/trial_physics.hpp"

namespace hattr::ops {

nlohmann::json ScriptedTrialResult::toJson() const {
  nlohmann::json json = profileSummaryJson(trial.profile);
  json["clamps"] = trial.clamps;
  json["missed_samples"] = trial.missed_samples;
  json["overruns"] = trial.overruns;
  json["faults"] = trial.faults;
  json["link_faults"] = trial.link_faults;
  json["stalls"] = trial.stalls;
  json["clock"] = trial.clock;
  json["end_reason"] = trial.end_reason;
  json["physical_events"] = physicalEventsJson(trial.physics);
  json["disturbed"] = disturbed;
  return json;
}

ScriptedTrialResult runScriptedTrial(ScriptedTrialRun run) {
  device::ProfileHandScript hand(run.hand);
  session::TrialEnvironment environment(run.device, std::move(run.world), run.options.rate_hz);
  const bool training = run.reference.has_value();
  run.options.expert = training ? &*run.reference : nullptr;
  session::TrialSetup setup = session::scriptedTrialSetup(hand, run.hand, run.options);
  if (training) {
    // A reference or a hand script the device cannot render is refused before the trial runs
    // (issue 38), checked against the limits of the device the trial opened; a recording keeps
    // any hand script: it records what happens, and marks it.
    const auto named = [](const std::string& what, const std::string& file) {
      return file.empty() ? what : fmt::format("{} {}", what, file);
    };
    setup.check_device = [&run, reference = named(run.reference_what, run.options.reference_label),
                          script = named(run.hand_what, run.options.hand_label)](const DeviceLimits& limits) {
      session::checkRenderable(*run.reference, limits, reference);
      session::checkRenderable(run.hand, limits, script);
    };
  }
  ScriptedTrialResult result;
  result.trial = session::runTrial(environment, setup, hand);
  result.disturbed = session::disturbanceOf(result.trial);
  result.mode = training ? std::string(guidance::modeName(setup.guidance.mode)) : std::string("expert");
  return result;
}

}  // namespace hattr::ops
