#pragma once
/// The paper's two scores of a trial against the expert (section 5.1), from one code path
/// for `hattr dtw --score`, the study report and the studio:
///   1. the writing span of each profile (metadata writing_begin_s..writing_end_s when the
///      trial recorded them: first pen-down to last pen-up; else the whole profile);
///   2. each channel normalized, the trial's span linearly time-scaled onto the expert's and
///      interpolated at the expert's time steps (preprocessTrial);
///   3. DTW per channel, absolute-difference cost (dtwBatch).
/// Shape is x + y: the character on the paper plane. The pen height z is scored on its own
/// and never counted in the shape. The haptic-profile score is fx + fy + fz.
/// Offline code: any thread but the servo thread. Throws InputError for profiles it cannot
/// score (fewer than 2 samples in the span, non-increasing times).

#include <array>
#include <span>
#include <vector>

#include "hattr/analysis/dtw.hpp"
#include "hattr/analysis/preprocess.hpp"
#include "hattr/core/haptic_profile.hpp"

namespace hattr::analysis {

struct ScoreOptions {
  Normalization normalization = Normalization::kPaper;
  DtwCost cost = DtwCost::kAbsolute;
  double band_fraction = -1.0;  ///< Sakoe–Chiba band (negative: none, the paper's)
  /// False: the pen height z is not scored (TrialScore::z is NaN), a sixth less DTW, for
  /// analyses that use only the shape and force (a power analysis).
  bool score_z = true;
  /// False: x and y (the shape), or fx, fy and fz (the haptic profile), are not scored (NaN),
  /// for an analysis of the other alone (a study plan of one outcome).
  bool score_shape = true;
  bool score_force = true;
  /// Whether channel k of TrialScore's order (x, y, z, fx, fy, fz) is scored.
  [[nodiscard]] bool scores(std::size_t k) const noexcept {
    return k == 2 ? score_z : k < 2 ? score_shape : score_force;
  }
};

/// One trial's DTW costs per channel (normalized units).
struct TrialScore {
  double x = 0.0, y = 0.0;              ///< the shape's channels
  double z = 0.0;                       ///< pen height, reported on its own
  double fx = 0.0, fy = 0.0, fz = 0.0;  ///< the haptic profile's channels
  [[nodiscard]] double shape() const noexcept { return x + y; }
  [[nodiscard]] double force() const noexcept { return fx + fy + fz; }
};

/// The span a profile is scored over [s]: its writing span when recorded, else all of it.
struct TimeSpan {
  double begin_s = 0.0;
  double end_s = 0.0;
};
[[nodiscard]] TimeSpan writingSpan(const HapticProfile& profile);

/// A trial's scored channels (x, y, z, fx, fy, fz) normalized and resampled onto the expert's
/// time steps (steps 1 and 2): what the DTW compares, a fraction of the trial's size.
struct PreparedTrial {
  std::array<std::vector<double>, 6> series;
};

/// Scores trials against one expert profile, whose channels are prepared once.
class TrialScorer {
 public:
  explicit TrialScorer(const HapticProfile& expert, ScoreOptions options = {});

  [[nodiscard]] TrialScore score(const HapticProfile& trial) const;
  /// Every trial at once, the trials (preprocessing) and then the six channels (DTW) shared
  /// by up to `threads` threads; the same numbers as score() on each.
  [[nodiscard]] std::vector<TrialScore> scoreAll(std::span<const HapticProfile* const> trials,
                                                 unsigned threads = 1) const;
  /// scoreAll in two steps, for trials scored as they end (a power analysis keeps the prepared
  /// channels, not the recordings): steps 1-2 of one trial, then step 3 of many. The same
  /// numbers as scoreAll, whichever trials are scored together.
  [[nodiscard]] PreparedTrial prepare(const HapticProfile& trial) const;
  [[nodiscard]] std::vector<TrialScore> scorePrepared(std::span<const PreparedTrial> trials,
                                                      unsigned threads = 1) const;
  /// The expert time steps each trial is resampled to.
  [[nodiscard]] std::size_t expertSamples() const noexcept { return expert_t_.size(); }
  [[nodiscard]] const ScoreOptions& options() const noexcept { return options_; }

 private:
  ScoreOptions options_;
  std::vector<double> expert_t_;
  std::array<std::vector<double>, 6> expert_series_;  ///< x, y, z, fx, fy, fz, normalized
};

}  // namespace hattr::analysis
