#pragma once
/// The studio's scores of a trial: analysis::TrialScorer, the one scorer `hattr dtw --score`
/// and the study report use (shape x + y, height z on its own, force fx + fy + fz), and a
/// line for people. Offline code: not for the servo thread; throws InputError for profiles
/// it cannot score.

#include <string>

#include "hattr/analysis/trial_score.hpp"
#include "hattr/core/haptic_profile.hpp"

namespace hattr::studio {

/// Scores `trial` against `expert` with the paper's settings.
analysis::TrialScore scoreTrial(const HapticProfile& expert, const HapticProfile& trial);

/// One line for people: "shape 12.3 (x 6.1, y 6.2) · height 1.2 · force 40.1 (fx 10.0, fy 12.0, fz 18.1)".
std::string describeScores(const analysis::TrialScore& scores);

}  // namespace hattr::studio
