// Normalization, linear time scaling and linear interpolation of trials (paper 5.1.1).

#include "hattr/analysis/preprocess.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string_view>

#include "hattr/core/error.hpp"

namespace hattr::analysis {

std::string_view normalizationName(Normalization how) {
  switch (how) {
    case Normalization::kPaper: return "paper";
    case Normalization::kZScore: return "zscore";
    case Normalization::kNone: return "none";
  }
  return "none";
}

Normalization parseNormalization(std::string_view name) {
  for (const Normalization how : {Normalization::kPaper, Normalization::kZScore, Normalization::kNone}) {
    if (name == normalizationName(how)) return how;
  }
  throw InputError(fmt::format("normalization \"{}\": expected paper, zscore or none", name));
}
namespace {

// Non-empty and finite; `what` names the function and the series.
void checkValues(std::string_view what, std::span<const double> values) {
  HATTR_THROW_UNLESS(!values.empty(), "{}: expected at least 1 value, got 0", what);
  for (std::size_t i = 0; i < values.size(); ++i) {
    HATTR_THROW_UNLESS(std::isfinite(values[i]), "{}[{}]: expected a finite number, got {}", what,
                       i, values[i]);
  }
}

// At least `min_count` finite, strictly increasing time stamps.
void checkTimes(std::string_view what, std::span<const double> t_s, std::size_t min_count) {
  HATTR_THROW_UNLESS(t_s.size() >= min_count, "{}: expected at least {} time stamps, got {}", what,
                     min_count, t_s.size());
  checkValues(what, t_s);
  for (std::size_t i = 1; i < t_s.size(); ++i) {
    HATTR_THROW_UNLESS(t_s[i] > t_s[i - 1],
                       "{}[{}]: expected strictly increasing time stamps, got {} s after {} s",
                       what, i, t_s[i], t_s[i - 1]);
  }
}

}  // namespace

std::vector<double> normalize(std::span<const double> values, Normalization how) {
  checkValues("normalize: values", values);
  std::vector<double> out(values.begin(), values.end());
  if (how == Normalization::kNone) return out;

  double sum = 0.0;
  for (const double v : values) sum += v;
  const double mean = sum / static_cast<double>(values.size());
  double scale = 0.0;
  if (how == Normalization::kPaper) {
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    scale = *hi - *lo;
  } else if (values.size() > 1) {
    double squares = 0.0;
    for (const double v : values) squares += (v - mean) * (v - mean);
    scale = std::sqrt(squares / static_cast<double>(values.size() - 1));
  }
  // A constant series has nothing to scale: all zeros.
  for (double& v : out) v = scale > 0.0 ? (v - mean) / scale : 0.0;
  return out;
}

std::vector<double> timeScale(std::span<const double> trial_t_s,
                              std::span<const double> expert_t_s) {
  checkTimes("timeScale: trial times", trial_t_s, 2);
  checkTimes("timeScale: expert times", expert_t_s, 2);
  const double t0 = trial_t_s.front();
  const double e0 = expert_t_s.front();
  const double factor = (expert_t_s.back() - e0) / (trial_t_s.back() - t0);
  std::vector<double> out;
  out.reserve(trial_t_s.size());
  for (const double t : trial_t_s) out.push_back(e0 + (t - t0) * factor);
  // The ends land exactly on the expert's, whatever the rounding.
  out.front() = e0;
  out.back() = expert_t_s.back();
  return out;
}

std::vector<double> interpolateAt(std::span<const double> t_s, std::span<const double> values,
                                  std::span<const double> at_t_s) {
  checkTimes("interpolateAt: times", t_s, 1);
  checkValues("interpolateAt: values", values);
  HATTR_THROW_UNLESS(values.size() == t_s.size(),
                     "interpolateAt: expected as many values as time stamps ({}), got {}",
                     t_s.size(), values.size());
  std::vector<double> out;
  out.reserve(at_t_s.size());
  std::size_t k = 0;
  for (std::size_t q = 0; q < at_t_s.size(); ++q) {
    const double t = at_t_s[q];
    HATTR_THROW_UNLESS(std::isfinite(t) && t >= t_s.front() && t <= t_s.back(),
                       "interpolateAt: query time [{}]: expected a time within [{}, {}] s, got {}",
                       q, t_s.front(), t_s.back(), t);
    // The segment [t_s[k-1], t_s[k]] holding t (k = 1 .. n-1; a one-point series is exact):
    // the first time after t. Queries in order (a trial at the expert's steps) walk on from the
    // last one's segment; others search.
    if (q > 0 && t >= at_t_s[q - 1]) {
      while (k < t_s.size() && t_s[k] <= t) ++k;
    } else {
      k = static_cast<std::size_t>(std::upper_bound(t_s.begin(), t_s.end(), t) - t_s.begin());
    }
    if (k >= t_s.size()) {
      out.push_back(values.back());
      continue;
    }
    const double w = (t - t_s[k - 1]) / (t_s[k] - t_s[k - 1]);
    out.push_back(values[k - 1] + w * (values[k] - values[k - 1]));
  }
  return out;
}

std::vector<double> preprocessTrial(std::span<const double> trial_t_s,
                                    std::span<const double> trial_values,
                                    std::span<const double> expert_t_s, Normalization how) {
  checkTimes("preprocessTrial: trial times", trial_t_s, 2);
  checkTimes("preprocessTrial: expert times", expert_t_s, 2);
  checkValues("preprocessTrial: trial values", trial_values);
  HATTR_THROW_UNLESS(trial_values.size() == trial_t_s.size(),
                     "preprocessTrial: expected as many trial values as trial time stamps ({}), "
                     "got {}",
                     trial_t_s.size(), trial_values.size());
  const std::vector<double> values = normalize(trial_values, how);
  const std::vector<double> scaled_t_s = timeScale(trial_t_s, expert_t_s);
  return interpolateAt(scaled_t_s, values, expert_t_s);
}

}  // namespace hattr::analysis
