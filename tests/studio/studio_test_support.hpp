#pragma once
// Shared helpers of the studio tests: a synthetic expert recorded through runTrial, a
// flat-paper environment (quick to build), temporary folders.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::studio::test {

/// A figure-eight written in `duration_s` (about 40 × 30 mm, centred on `centre`), pressing
/// with `normal_N` on the paper, sampled at 200 Hz: a hand script for ProfileHandScript.
HapticProfile figureEightScript(double duration_s = 1.2, double normal_N = 0.8, Vec3 centre = Vec3::Zero());

/// A world with flat paper (no relief to build) and the default friction and texture.
render::WorldConfig flatWorld();

/// The expert: the figure-eight recorded through session::runTrial in simulated time.
HapticProfile recordExpert(session::TrialEnvironment& environment, double duration_s = 1.2);

/// A small study file over the expert "expert.csv" (skill "eight"), one training and one
/// recall trial per mode, fixed order, on sim://pen at 1 kHz. `modes` and `subjects` are
/// JSON arrays; `relief` a relief kind ("flat", "grain"); `trial_end` the protocol's keys for
/// the end of a trial: an old file's fixed window (`"tail_s": 0.2`, the default) or an end
/// rule (`"trial_end": {"pen_up_s": 0.4}`).
/// A design for the studio (skill "eight", expert.csv): person P01 in one group trained with
/// PCONTROL; session 1 on day 0 (a training trial, a post-test trial), session 2 on day 1 (a
/// retention trial); rests of `rest_s`; trials end 0.5 s after the pen lifts.
std::string designStudyJson(double rest_s);

/// `mentor`: the study's mentor block (a JSON object), none when empty.
std::string smallStudyJson(const std::string& modes, double rest_s, const std::string& subjects,
                           const std::string& relief, const std::string& trial_end = "\"tail_s\": 0.2",
                           const std::string& mentor = "");

/// `writing` followed by the hand lifting the pen 5 mm where it ended and holding it there for
/// `lift_s` (a hand script for a trial that ends by the pen-up rule), sampled at 100 Hz.
HapticProfile writeThenLift(const HapticProfile& writing, double lift_s);

/// tests/support/host_stalls.hpp for Qt Test. One attempt of a real-time test: returns its
/// failures ("" when it passed) and sets the host stalls its loop counted.
using RealTimeAttempt = std::function<std::string(std::uint64_t& host_stalls)>;
struct RealTimeOutcome {
  bool passed = false;
  bool every_attempt_stalled = false;  ///< failed only with stalls: the test is to be skipped
  std::string failures;                ///< the last attempt's
};
/// Runs `attempt` until one passes, at most `tries` times; an attempt that fails without a
/// stall ends it at once (a failure of the test's own).
RealTimeOutcome passesUnlessTheHostStalls(const RealTimeAttempt& attempt, int tries = 3);

/// A study database `dir`/s.sqlite for the report (3 scripted subjects, 3 modes, 1 training
/// + 3 recall trials each, over a short expert curve), run to the end by StudyRunner when
/// `complete`, else left with every trial to do.
std::filesystem::path reportStudy(const std::filesystem::path& dir, bool complete, int subjects = 3);

/// A fresh empty folder under the system's temporary folder.
std::filesystem::path freshTempDir(const std::string& name);

}  // namespace hattr::studio::test
