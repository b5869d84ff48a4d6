#include "hattr/analysis/trial_score.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <string>

#include "hattr/core/error.hpp"
#include "parallel.hpp"

namespace hattr::analysis {
namespace {

constexpr std::array<Channel, 6> kScoredChannels{Channel::kX,  Channel::kY,  Channel::kZ,
                                                 Channel::kFx, Channel::kFy, Channel::kFz};

/// A metadata number [s]; false when absent or not a finite number.
bool readSeconds(const HapticProfile& profile, const char* key, double& value) {
  const auto& extra = profile.metadata().extra;
  const auto it = extra.find(key);
  if (it == extra.end()) return false;
  const std::string& text = it->second;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v)) return false;
  value = v;
  return true;
}

/// The scored channels of a profile within its writing span, and their times.
struct Cropped {
  std::vector<double> t_s;
  std::array<std::vector<double>, 6> series;
};

Cropped crop(const HapticProfile& profile, const char* who) {
  const TimeSpan span = writingSpan(profile);
  const std::vector<double> t = profile.channel(Channel::kTime);
  const auto first = std::lower_bound(t.begin(), t.end(), span.begin_s) - t.begin();
  const auto last = std::upper_bound(t.begin(), t.end(), span.end_s) - t.begin();
  HATTR_THROW_UNLESS(last - first >= 2, "scoring: the {} has {} samples in its writing span [{}, {}] s, expected at least 2",
                     who, std::max<std::ptrdiff_t>(0, last - first), span.begin_s, span.end_s);
  Cropped c;
  c.t_s.assign(t.begin() + first, t.begin() + last);
  for (std::size_t k = 0; k < kScoredChannels.size(); ++k) {
    const std::vector<double> all = profile.channel(kScoredChannels[k]);
    c.series[k].assign(all.begin() + first, all.begin() + last);
  }
  return c;
}

}  // namespace

TimeSpan writingSpan(const HapticProfile& profile) {
  TimeSpan span{-INFINITY, INFINITY};
  if (!profile.empty()) span = {profile.samples().front().t_s, profile.samples().back().t_s};
  double begin = 0.0;
  double end = 0.0;
  if (readSeconds(profile, "writing_begin_s", begin) && readSeconds(profile, "writing_end_s", end) && end > begin) {
    span = {begin, end};
  }
  return span;
}

TrialScorer::TrialScorer(const HapticProfile& expert, ScoreOptions options) : options_(options) {
  Cropped c = crop(expert, "expert profile");
  expert_t_ = std::move(c.t_s);
  for (std::size_t k = 0; k < kScoredChannels.size(); ++k) expert_series_[k] = normalize(c.series[k], options_.normalization);
}

TrialScore TrialScorer::score(const HapticProfile& trial) const {
  const HapticProfile* one[] = {&trial};
  return scoreAll(one, 1).front();
}

std::vector<TrialScore> TrialScorer::scoreAll(std::span<const HapticProfile* const> trials, unsigned threads) const {
  // Each trial's span preprocessed onto the expert's time steps, the trials shared by the threads.
  std::vector<PreparedTrial> prepared(trials.size());
  detail::forEachChunk(trials.size(), 1, std::max(1u, threads),
                       [&](std::size_t i, std::size_t) { prepared[i] = prepare(*trials[i]); });
  return scorePrepared(prepared, threads);
}

PreparedTrial TrialScorer::prepare(const HapticProfile& trial) const {
  const Cropped c = crop(trial, "trial");
  // preprocessTrial channel by channel, the trial's times scaled onto the expert's span once.
  const std::vector<double> scaled_t_s = timeScale(c.t_s, expert_t_);
  PreparedTrial p;
  for (std::size_t k = 0; k < kScoredChannels.size(); ++k) {
    if (!options_.scores(k)) continue;  // left empty: not scored
    p.series[k] = interpolateAt(scaled_t_s, normalize(c.series[k], options_.normalization), expert_t_);
  }
  return p;
}

std::vector<TrialScore> TrialScorer::scorePrepared(std::span<const PreparedTrial> trials, unsigned threads) const {
  // DTW per channel, each channel's trials as one batch read in place, the channels shared by
  // the threads; z (or the shape's, or the force's) only when asked.
  const DtwOptions dtw{.cost = options_.cost, .band_fraction = options_.band_fraction};
  std::array<std::vector<double>, 6> costs;
  detail::forEachChunk(costs.size(), 1, std::max(1u, threads), [&](std::size_t k, std::size_t) {
    if (!options_.scores(k)) {
      costs[k].assign(trials.size(), std::numeric_limits<double>::quiet_NaN());
      return;
    }
    const std::vector<std::span<const double>> expert(trials.size(), expert_series_[k]);
    std::vector<std::span<const double>> trial(trials.size());
    for (std::size_t i = 0; i < trials.size(); ++i) trial[i] = trials[i].series[k];
    costs[k] = dtwBatch(expert, trial, dtw);
  });

  std::vector<TrialScore> scores(trials.size());
  for (std::size_t i = 0; i < trials.size(); ++i) {
    scores[i] = {costs[0][i], costs[1][i], costs[2][i], costs[3][i], costs[4][i], costs[5][i]};
  }
  return scores;
}

}  // namespace hattr::analysis
