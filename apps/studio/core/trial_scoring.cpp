#include "core/trial_scoring.hpp"

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::studio {
namespace {

/// One group of channels of both profiles, preprocessed as `hattr dtw` does: the expert's
/// normalized, the trial's preprocessed onto the expert's time stamps.
std::vector<double> scoreGroup(const HapticProfile& expert, const HapticProfile& trial,
                               std::initializer_list<Channel> channels, analysis::Normalization how,
                               const analysis::DtwOptions& options) {
  const std::vector<double> expert_t = expert.channel(Channel::kTime);
  const std::vector<double> trial_t = trial.channel(Channel::kTime);
  std::vector<std::vector<double>> a;
  std::vector<std::vector<double>> b;
  for (const Channel channel : channels) {
    a.push_back(analysis::normalize(expert.channel(channel), how));
    b.push_back(analysis::preprocessTrial(trial_t, trial.channel(channel), expert_t, how));
  }
  return analysis::dtwIndependent(a, b, options);
}

}  // namespace

TrialScores scoreTrial(const HapticProfile& expert, const HapticProfile& trial, analysis::Normalization how,
                       const analysis::DtwOptions& options) {
  HATTR_THROW_UNLESS(expert.size() >= 2, "scoring: the expert profile needs at least 2 samples, got {}", expert.size());
  HATTR_THROW_UNLESS(trial.size() >= 2, "scoring: the trial needs at least 2 samples, got {}", trial.size());
  TrialScores scores;
  const std::vector<double> shape = scoreGroup(expert, trial, {Channel::kX, Channel::kY}, how, options);
  const std::vector<double> force = scoreGroup(expert, trial, {Channel::kFx, Channel::kFy, Channel::kFz}, how, options);
  scores.x = shape[0];
  scores.y = shape[1];
  scores.fx = force[0];
  scores.fy = force[1];
  scores.fz = force[2];
  scores.shape = scores.x + scores.y;
  scores.force = scores.fx + scores.fy + scores.fz;
  scores.expert_samples = expert.size();
  return scores;
}

std::string describeScores(const TrialScores& s) {
  return fmt::format("shape {:.4g} (x {:.4g}, y {:.4g}) · force {:.4g} (fx {:.4g}, fy {:.4g}, fz {:.4g})", s.shape, s.x,
                     s.y, s.force, s.fx, s.fy, s.fz);
}

}  // namespace hattr::studio
