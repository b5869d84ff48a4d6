// Handwriting kinematics of one trial (kinematics.hpp, docs/analysis.md).

#include "hattr/analysis/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"

namespace hattr::analysis {
namespace {

/// A second-order section: y = b0 x + z1; z1' = b1 x − a1 y + z2; z2' = b2 x − a2 y.
struct Biquad {
  double b0, b1, b2, a1, a2;
};

/// Butterworth low-pass by the bilinear transform with pre-warping.
Biquad butterworth(double cutoff_hz, double rate_hz) {
  const double k = std::tan(std::numbers::pi * cutoff_hz / rate_hz);
  const double norm = 1.0 / (1.0 + std::numbers::sqrt2 * k + k * k);
  const double b0 = k * k * norm;
  return {b0, 2.0 * b0, b0, 2.0 * (k * k - 1.0) * norm, (1.0 - std::numbers::sqrt2 * k + k * k) * norm};
}

/// One pass over x, started in the steady state of a line: the filter's response to a line
/// is the line delayed by its group delay at 0 Hz, τ, so the pass starts as if the line had
/// always been its input (a constant and a line come out with no transient; the backward
/// pass cancels τ). The line is the least-squares line through the first `fit` samples, so
/// measurement noise moves the start little (a two-sample slope, times τ of some 20
/// samples, would amplify it).
void filterPass(const Biquad& f, std::vector<double>& x, std::size_t fit) {
  fit = std::min(fit, x.size());
  double mean_k = 0.0, mean_x = 0.0;
  for (std::size_t k = 0; k < fit; ++k) {
    mean_k += static_cast<double>(k);
    mean_x += x[k];
  }
  mean_k /= static_cast<double>(fit);
  mean_x /= static_cast<double>(fit);
  double sxy = 0.0, sxx = 0.0;
  for (std::size_t k = 0; k < fit; ++k) {
    sxy += (static_cast<double>(k) - mean_k) * (x[k] - mean_x);
    sxx += (static_cast<double>(k) - mean_k) * (static_cast<double>(k) - mean_k);
  }
  const double slope = sxx > 0.0 ? sxy / sxx : 0.0;  // per sample
  const double x0 = mean_x - slope * mean_k;          // the line at the first sample
  const double tau = (f.b1 + 2.0 * f.b2) / (f.b0 + f.b1 + f.b2) - (f.a1 + 2.0 * f.a2) / (1.0 + f.a1 + f.a2);
  const double y0 = x0 - slope * tau;
  const double y1 = x0 + slope * (1.0 - tau);
  double z1 = y0 - f.b0 * x0;
  double z2 = y1 - f.b0 * (x0 + slope) - f.b1 * x0 + f.a1 * y0;
  for (double& v : x) {
    const double in = v;
    const double out = f.b0 * in + z1;
    z1 = f.b1 * in - f.a1 * out + z2;
    z2 = f.b2 * in - f.a2 * out;
    v = out;
  }
}

/// A stroke: the indices [begin, end) of a run of pen-down samples.
struct Stroke {
  std::size_t begin = 0;
  std::size_t end = 0;
  [[nodiscard]] std::size_t size() const { return end - begin; }
};

std::vector<Stroke> strokesOf(const std::vector<Sample>& samples) {
  std::vector<Stroke> strokes;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!samples[i].pen_down) continue;
    if (strokes.empty() || strokes.back().end != i) strokes.push_back({i, i});
    strokes.back().end = i + 1;
  }
  return strokes;
}

/// Central differences of a series in time (one-sided at the ends).
std::vector<double> derivative(const std::vector<double>& t, const std::vector<double>& x) {
  const std::size_t n = x.size();
  std::vector<double> d(n, 0.0);
  if (n < 2) return d;
  d.front() = (x[1] - x[0]) / (t[1] - t[0]);
  d.back() = (x[n - 1] - x[n - 2]) / (t[n - 1] - t[n - 2]);
  for (std::size_t i = 1; i + 1 < n; ++i) d[i] = (x[i + 1] - x[i - 1]) / (t[i + 1] - t[i - 1]);
  return d;
}

/// Local maxima of a series: a sample (or a run of equal samples) higher than both
/// neighbours; the ends are not counted.
std::size_t localMaxima(const std::vector<double>& v) {
  std::size_t count = 0;
  for (std::size_t i = 1; i + 1 < v.size(); ++i) {
    if (!(v[i] > v[i - 1])) continue;
    std::size_t j = i;
    while (j + 1 < v.size() && v[j + 1] == v[i]) ++j;  // a plateau counts once
    if (j + 1 < v.size() && v[j + 1] < v[i]) ++count;
    i = j;
  }
  return count;
}

/// A stroke's jerk needs this many samples: the filter's padding plus one, so it is measured on
/// filtered positions, and the third difference central over at least 3 samples.
constexpr std::size_t kJerkSamples = 10;

/// One stroke's measures.
struct StrokeMeasures {
  double length_m = 0.0;
  double peak_speed = 0.0;
  std::size_t peaks = 0;
  double normalized_jerk = std::numeric_limits<double>::quiet_NaN();
};

StrokeMeasures measureStroke(const std::vector<Sample>& samples, const Stroke& s, double cutoff_hz) {
  std::vector<double> t;
  std::vector<double> x;
  std::vector<double> y;
  for (std::size_t i = s.begin; i < s.end; ++i) {
    t.push_back(samples[i].t_s);
    x.push_back(samples[i].p_WT.x());
    y.push_back(samples[i].p_WT.y());
  }
  StrokeMeasures m;
  const std::size_t n = t.size();
  if (n < 2) return m;
  // Filtered where the stroke is sampled fast enough for the cut-off (a slow or gappy stroke
  // is measured raw: never an error in the middle of a study).
  const double rate_hz = static_cast<double>(n - 1) / (t.back() - t.front());
  if (cutoff_hz > 0.0 && cutoff_hz < rate_hz / 2.0) {
    x = lowPassZeroPhase(x, cutoff_hz, rate_hz);
    y = lowPassZeroPhase(y, cutoff_hz, rate_hz);
  }
  for (std::size_t i = 1; i < n; ++i) m.length_m += std::hypot(x[i] - x[i - 1], y[i] - y[i - 1]);

  // Tangential speed, its peaks; jerk by three successive central differences.
  const std::vector<double> vx = derivative(t, x);
  const std::vector<double> vy = derivative(t, y);
  std::vector<double> speed(n);
  for (std::size_t i = 0; i < n; ++i) speed[i] = std::hypot(vx[i], vy[i]);
  m.peak_speed = *std::max_element(speed.begin(), speed.end());
  m.peaks = localMaxima(speed);
  if (n < kJerkSamples) return m;
  const std::vector<double> jx = derivative(t, derivative(t, vx));
  const std::vector<double> jy = derivative(t, derivative(t, vy));
  // The third difference is central (exact on a cubic) from sample 3 to n − 4: the jerk, its
  // duration and its length are all taken over that interval.
  double integral = 0.0;
  double length = 0.0;
  for (std::size_t i = 3; i + 4 < n; ++i) {
    const double a = jx[i] * jx[i] + jy[i] * jy[i];
    const double b = jx[i + 1] * jx[i + 1] + jy[i + 1] * jy[i + 1];
    integral += 0.5 * (a + b) * (t[i + 1] - t[i]);
    length += std::hypot(x[i + 1] - x[i], y[i + 1] - y[i]);
  }
  const double duration = t[n - 4] - t[3];
  if (length > 0.0) m.normalized_jerk = std::sqrt(0.5 * integral * std::pow(duration, 5) / (length * length));
  return m;
}

}  // namespace

std::vector<double> lowPassZeroPhase(const std::vector<double>& x, double cutoff_hz, double rate_hz) {
  constexpr std::size_t kPad = 9;  // SciPy's filtfilt: 3 × max(len(a), len(b))
  const std::size_t n = x.size();
  if (n <= kPad) return x;  // too short to pad: left as it is
  HATTR_THROW_UNLESS(std::isfinite(cutoff_hz) && cutoff_hz > 0.0 && cutoff_hz < rate_hz / 2.0,
                     "low-pass filter: cut-off {} Hz; expected above 0 and below half the sampling rate ({} Hz)",
                     cutoff_hz, rate_hz / 2.0);
  // Odd reflection about each end: 2 x0 − x[k], so a line continues as a line.
  std::vector<double> padded;
  padded.reserve(n + 2 * kPad);
  for (std::size_t k = kPad; k >= 1; --k) padded.push_back(2.0 * x.front() - x[k]);
  padded.insert(padded.end(), x.begin(), x.end());
  for (std::size_t k = 1; k <= kPad; ++k) padded.push_back(2.0 * x.back() - x[n - 1 - k]);
  const Biquad f = butterworth(cutoff_hz, rate_hz);
  filterPass(f, padded, 2 * kPad + 1);
  std::reverse(padded.begin(), padded.end());
  filterPass(f, padded, 2 * kPad + 1);
  std::reverse(padded.begin(), padded.end());
  return {padded.begin() + static_cast<std::ptrdiff_t>(kPad), padded.end() - static_cast<std::ptrdiff_t>(kPad)};
}

TrialKinematics trialKinematics(const HapticProfile& profile, const KinematicsOptions& options) {
  HATTR_THROW_UNLESS(std::isfinite(options.cutoff_hz) && options.cutoff_hz >= 0.0,
                     "kinematics: cut-off {} Hz; expected 0 (no filter) or a positive frequency", options.cutoff_hz);
  const std::vector<Sample>& samples = profile.samples();
  TrialKinematics k;
  k.duration_s = profile.duration_s();
  const std::vector<Stroke> strokes = strokesOf(samples);
  k.normalized_jerk = std::numeric_limits<double>::quiet_NaN();
  if (strokes.empty()) return k;
  k.strokes = strokes.size();
  k.pen_lifts = strokes.size() - 1;

  double jerk_sum = 0.0;
  std::size_t jerk_strokes = 0;
  double force_sum = 0.0;
  std::size_t down = 0;
  for (const Stroke& s : strokes) {
    k.writing_time_s += samples[s.end - 1].t_s - samples[s.begin].t_s;
    const StrokeMeasures m = measureStroke(samples, s, options.cutoff_hz);
    k.path_length_m += m.length_m;
    k.peak_speed_m_per_s = std::max(k.peak_speed_m_per_s, m.peak_speed);
    k.velocity_peaks += m.peaks;
    if (std::isfinite(m.normalized_jerk)) {
      jerk_sum += m.normalized_jerk;
      ++jerk_strokes;
    }
    for (std::size_t i = s.begin; i < s.end; ++i) {
      const double press = -samples[i].f_user_W.z();
      force_sum += press;
      k.peak_normal_force_N = std::max(k.peak_normal_force_N, press);
      ++down;
    }
  }
  const double first_down = samples[strokes.front().begin].t_s;
  const double last_up = samples[strokes.back().end - 1].t_s;
  k.in_air_time_s = (last_up - first_down) - k.writing_time_s;
  k.mean_speed_m_per_s = k.writing_time_s > 0.0 ? k.path_length_m / k.writing_time_s : 0.0;
  k.mean_normal_force_N = force_sum / static_cast<double>(down);
  if (jerk_strokes > 0) k.normalized_jerk = jerk_sum / static_cast<double>(jerk_strokes);
  return k;
}

const std::vector<const char*>& kinematicsNames() {
  static const std::vector<const char*> names{
      "duration_s",          "writing_time_s",     "in_air_time_s",   "strokes",
      "pen_lifts",           "path_length_m",      "mean_speed_m_per_s", "peak_speed_m_per_s",
      "velocity_peaks",      "normalized_jerk",    "mean_normal_force_N", "peak_normal_force_N"};
  return names;
}

bool isKinematicsName(std::string_view name) {
  const auto& names = kinematicsNames();
  return std::any_of(names.begin(), names.end(), [name](const char* n) { return name == n; });
}

nlohmann::json toJson(const TrialKinematics& k) {
  return nlohmann::json{{"duration_s", jsonNumber(k.duration_s)},
                        {"writing_time_s", jsonNumber(k.writing_time_s)},
                        {"in_air_time_s", jsonNumber(k.in_air_time_s)},
                        {"strokes", k.strokes},
                        {"pen_lifts", k.pen_lifts},
                        {"path_length_m", jsonNumber(k.path_length_m)},
                        {"mean_speed_m_per_s", jsonNumber(k.mean_speed_m_per_s)},
                        {"peak_speed_m_per_s", jsonNumber(k.peak_speed_m_per_s)},
                        {"velocity_peaks", k.velocity_peaks},
                        {"normalized_jerk", jsonNumber(k.normalized_jerk)},
                        {"mean_normal_force_N", jsonNumber(k.mean_normal_force_N)},
                        {"peak_normal_force_N", jsonNumber(k.peak_normal_force_N)}};
}

}  // namespace hattr::analysis
