#pragma once
/// The paper's scores of a trial against the expert (section 5.1): each channel of the
/// trial normalized, time-scaled onto the expert's span and interpolated at the expert's
/// time stamps (analysis::preprocessTrial); the expert's channel normalized the same way;
/// then DTW per channel (analysis::dtwIndependent). The shape score sums x and y, the force
/// score sums fx, fy and fz. Exactly what `hattr dtw A B --channels x,y,fx,fy,fz` computes.
/// Offline code: not for the servo thread; throws InputError for profiles it cannot score.

#include <string>
#include <vector>

#include "hattr/analysis/dtw.hpp"
#include "hattr/analysis/preprocess.hpp"
#include "hattr/core/haptic_profile.hpp"

namespace hattr::studio {

struct TrialScores {
  double x = 0.0, y = 0.0;              ///< DTW cost per position channel (normalized units)
  double fx = 0.0, fy = 0.0, fz = 0.0;  ///< DTW cost per force channel (normalized units)
  double shape = 0.0;                   ///< x + y
  double force = 0.0;                   ///< fx + fy + fz
  std::size_t expert_samples = 0;       ///< the length the trial was resampled to
};

/// Scores `trial` against `expert`. Throws hattr::InputError when either has fewer than two
/// samples or non-increasing times (the message names which).
TrialScores scoreTrial(const HapticProfile& expert, const HapticProfile& trial,
                       analysis::Normalization how = analysis::Normalization::kPaper,
                       const analysis::DtwOptions& options = {});

/// One line for people: "shape 12.3 (x 6.1, y 6.2) · force 40.1 (fx 10.0, fy 12.0, fz 18.1)".
std::string describeScores(const TrialScores& scores);

}  // namespace hattr::studio
