#include "hattr/guidance/strategy_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>

namespace hattr::guidance {
namespace {

/// FADING by trials: start to end, linearly, reached at guided trial `trials` (from 1).
double fadedByTrials(const FadingConfig& f, std::size_t done) {
  if (f.trials <= 1.0) return f.end_gain;  // reached at the first guided trial
  const double share = std::min(1.0, static_cast<double>(done) / (f.trials - 1.0));
  return f.start_gain + (f.end_gain - f.start_gain) * share;
}

/// FADING by performance: a step toward end_gain after each good trial.
double fadedByPerformance(const FadingConfig& f, std::span<const double> errors_m) {
  const double direction = f.end_gain < f.start_gain ? -1.0 : 1.0;
  double gain = f.start_gain;
  for (const double e : errors_m) {
    if (!(e <= f.threshold_m)) continue;  // not good enough (or nothing written): the gain stays
    gain += direction * f.step;
    gain = direction < 0.0 ? std::max(gain, f.end_gain) : std::min(gain, f.end_gain);
  }
  return gain;
}

/// ASSIST-AS-NEEDED: the error-based update with forgetting, from the first trial on.
double assisted(const AssistAsNeededConfig& a, std::span<const double> errors_m) {
  double gain = a.start_gain;
  for (const double e : errors_m) {
    // An error beyond any (nothing written) adds full assistance, unless errors add none.
    const double excess = std::isnan(e) ? 0.0 : std::max(0.0, e - a.deadband_m);
    const double added = a.error_gain_per_m > 0.0 ? a.error_gain_per_m * excess : 0.0;
    gain = std::clamp(a.forgetting * gain + added, 0.0, 1.0);
  }
  return gain;
}

}  // namespace

ScheduledLaw scheduleTrial(const GuidanceConfig& config, TrainingMode mode, std::span<const double> errors_before_m) {
  switch (mode) {
    case TrainingMode::kFading: {
      const FadingConfig& f = config.fading;
      const double gain = f.by == FadingConfig::By::kTrials ? fadedByTrials(f, errors_before_m.size())
                                                            : fadedByPerformance(f, errors_before_m);
      return {f.base, std::clamp(gain, 0.0, 1.0)};
    }
    case TrainingMode::kAssistAsNeeded: return {config.assist.base, assisted(config.assist, errors_before_m)};
    case TrainingMode::kPartialThenFull: {
      const bool partial = static_cast<double>(errors_before_m.size()) < config.partial_then_full.partial_trials;
      return {partial ? TrainingMode::kChannel : TrainingMode::kPositionControl, 1.0};
    }
    default: return config.scheduled;  // not scheduled: nothing to choose
  }
}

double trackingErrorRms(const ReferenceTrajectory& reference, const HapticProfile& trial) {
  // The expert's path: its pen-down points in the plane.
  std::vector<Eigen::Vector2d> path;
  path.reserve(reference.size());
  for (std::size_t k = 0; k < reference.size(); ++k) {
    if (reference[k].pen_down) path.push_back(reference[k].p_WT.head<2>());
  }
  if (path.empty()) {
    for (std::size_t k = 0; k < reference.size(); ++k) path.push_back(reference[k].p_WT.head<2>());
  }
  // Each pen-down sample's squared distance to its nearest point of the path.
  double sum_sq = 0.0;
  std::size_t count = 0;
  for (const Sample& s : trial.samples()) {
    if (!s.pen_down) continue;
    const Eigen::Vector2d p = s.p_WT.head<2>();
    double nearest_sq = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2d& q : path) nearest_sq = std::min(nearest_sq, (p - q).squaredNorm());
    sum_sq += nearest_sq;
    ++count;
  }
  if (count == 0) return std::numeric_limits<double>::infinity();
  return std::sqrt(sum_sq / static_cast<double>(count));
}

}  // namespace hattr::guidance
