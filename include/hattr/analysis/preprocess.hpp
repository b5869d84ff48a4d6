#pragma once
/// Preprocessing of a trial before it is compared with the expert's (paper, section
/// 5.1.1): normalize the trial's values, stretch or shrink its time axis linearly so that
/// its duration matches the expert's, and linearly interpolate it onto the expert's time
/// stamps, so that both series have one value per expert time step.
///
/// Times are in seconds [s]; values in any unit (normalization makes them dimensionless,
/// kNone keeps the unit). Plain std::vector / std::span of doubles, no dependency beyond
/// core. Offline analysis code: any thread but the servo thread; thread-safe. Bad input
/// throws hattr::InputError saying which series, which index, what was expected and got.

#include <span>
#include <string_view>
#include <vector>

namespace hattr::analysis {

/// How values are normalized.
enum class Normalization {
  /// Our reading of the paper's normalization: (x - mean) / (max - min), i.e. centred on
  /// the series' mean and divided by its range. A constant series becomes all zeros.
  kPaper,
  /// (x - mean) / sd with the sample standard deviation (n - 1 denominator, as R's
  /// scale()). A constant or one-point series becomes all zeros.
  kZScore,
  /// Values unchanged.
  kNone,
};

/// The name of a normalization as files, the CLI and Python spell it: "paper", "zscore", "none".
[[nodiscard]] std::string_view normalizationName(Normalization how);
/// The normalization with that name; throws InputError listing the names otherwise.
[[nodiscard]] Normalization parseNormalization(std::string_view name);

/// The values normalized as `how` says. Throws InputError if empty or not all finite.
[[nodiscard]] std::vector<double> normalize(std::span<const double> values, Normalization how);

/// The trial's time stamps mapped linearly onto the expert's time span: the first trial
/// time goes to the first expert time, the last to the last, and in between
/// t' = e_0 + (t - t_0) * (e_last - e_0) / (t_last - t_0) [s]. Both need at least 2
/// finite, strictly increasing time stamps; throws InputError otherwise.
[[nodiscard]] std::vector<double> timeScale(std::span<const double> trial_t_s,
                                            std::span<const double> expert_t_s);

/// Linear interpolation of the series (t_s, values) at the times `at_t_s` [s]. t_s must be
/// finite and strictly increasing (at least 1 point), values finite and as many as t_s,
/// and every query time finite and within [t_s.front(), t_s.back()]. Throws InputError
/// otherwise.
[[nodiscard]] std::vector<double> interpolateAt(std::span<const double> t_s,
                                                std::span<const double> values,
                                                std::span<const double> at_t_s);

/// The paper's preprocessing of one trial: normalize(trial_values, how), time-scaled onto
/// the expert's span with timeScale(), interpolated at every expert time stamp. Returns
/// one value per expert time stamp. Throws InputError on empty series, mismatched
/// lengths of times and values, non-finite numbers, fewer than 2 samples, or time stamps
/// that do not strictly increase.
[[nodiscard]] std::vector<double> preprocessTrial(std::span<const double> trial_t_s,
                                                  std::span<const double> trial_values,
                                                  std::span<const double> expert_t_s,
                                                  Normalization how = Normalization::kPaper);

}  // namespace hattr::analysis
