#pragma once
/// The studio's scores of a trial: analysis::TrialScorer, the one scorer `hattr dtw --score`
/// and the study report use (shape x + y, height z on its own, force fx + fy + fz). Offline
/// code: not for the servo thread; throws InputError for profiles it cannot score.

#include "hattr/analysis/trial_score.hpp"
#include "hattr/core/haptic_profile.hpp"

namespace hattr::studio {

/// Scores `trial` against `expert` with the paper's settings.
analysis::TrialScore scoreTrial(const HapticProfile& expert, const HapticProfile& trial);

}  // namespace hattr::studio
