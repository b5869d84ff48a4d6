#pragma once
/// Handwriting kinematics of one trial: the fluency and timing measures the handwriting
/// literature reports beside shape (Teulings and Maarse 1984; Teulings, Contreras-Vidal,
/// Stelmach and Adler 1997; Palluel-Germain et al. 2007; Bluteau et al. 2008): durations,
/// pen lifts, path length, speeds, the number of velocity peaks, normalized jerk and the
/// normal force. docs/analysis.md gives each definition, the filter and its sources.
///
/// Everything is measured over the pen-down samples, split into strokes (maximal runs of
/// pen-down samples). Positions in the paper plane (x, y) are low-passed per stroke by a
/// zero-phase second-order Butterworth filter (forward and backward) before they are
/// differentiated; `cutoff_hz = 0` measures the raw samples.
///
/// Offline analysis code: any thread but the servo thread; no shared state.

#include <cstddef>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::analysis {

struct KinematicsOptions {
  double cutoff_hz = 10.0;  ///< the low-pass filter's cut-off [Hz]; 0: no filter
};

struct TrialKinematics {
  double duration_s = 0.0;       ///< first sample to last
  double writing_time_s = 0.0;   ///< the strokes' durations summed (pen down)
  double in_air_time_s = 0.0;    ///< between the strokes: first pen-down to last pen-up, less writing time
  std::size_t strokes = 0;       ///< runs of pen-down samples
  std::size_t pen_lifts = 0;     ///< lifts between strokes: strokes − 1 (0 when nothing was written)
  double path_length_m = 0.0;    ///< the strokes' lengths in the paper plane, summed
  double mean_speed_m_per_s = 0.0;  ///< path length / writing time
  double peak_speed_m_per_s = 0.0;  ///< the largest tangential speed while writing
  std::size_t velocity_peaks = 0;   ///< NVP: local maxima of the tangential speed inside the strokes
  /// Teulings et al.'s normalized jerk √(½ ∫|j|² dt · T⁵ / L²), dimensionless, per stroke over
  /// the samples where the third difference is central (the 4th to the 4th-last; T and L
  /// over the same), averaged over the strokes of 10 samples or more; NaN when there is none.
  double normalized_jerk = 0.0;
  double mean_normal_force_N = 0.0;  ///< the pen's press on the paper (−f_user z), mean over pen-down samples
  double peak_normal_force_N = 0.0;  ///< its largest value
};

/// The kinematics of a profile. A profile with nothing written gives zeros (and a NaN jerk).
/// Throws InputError for a negative or non-finite cut-off only: a stroke sampled slower than
/// twice the cut-off is measured unfiltered.
[[nodiscard]] TrialKinematics trialKinematics(const HapticProfile& profile, const KinematicsOptions& options = {});

/// The measures by name, in SI units, for JSON and tables ("duration_s", "pen_lifts", ...):
/// one order, used by `hattr kinematics`, the study's long table and Python.
[[nodiscard]] nlohmann::json toJson(const TrialKinematics& k);

/// The measures' names in that order.
[[nodiscard]] const std::vector<const char*>& kinematicsNames();
/// Whether `name` is one of them.
[[nodiscard]] bool isKinematicsName(std::string_view name);

/// A series low-passed by a zero-phase second-order Butterworth filter (forward then
/// backward over the series extended by an odd reflection of 9 samples at each end, as
/// SciPy's filtfilt; each pass started in the steady state of the least-squares line through
/// its first 19 samples, where filtfilt starts at a constant's, so a line passes unchanged).
/// `rate_hz` is the sampling rate. A series of 9 samples or fewer is returned as it is;
/// otherwise throws InputError unless 0 < cutoff_hz < rate_hz / 2. Exposed for its tests.
[[nodiscard]] std::vector<double> lowPassZeroPhase(const std::vector<double>& x, double cutoff_hz, double rate_hz);

}  // namespace hattr::analysis
