#include "hattr/guidance/reference.hpp"

#include <algorithm>
#include <cmath>

#include "hattr/core/error.hpp"

namespace hattr::guidance {

ReferenceTrajectory::ReferenceTrajectory(const HapticProfile& expert, double rate_hz) {
  HATTR_THROW_UNLESS(expert.size() >= 2, "reference: expected a profile with at least 2 samples, got {}", expert.size());
  HATTR_THROW_UNLESS(std::isfinite(rate_hz) && rate_hz >= 1.0 && rate_hz <= 10'000.0,
                     "reference: servo rate: expected 1 to 10000 Hz, got {}", rate_hz);
  dt_s_ = 1.0 / rate_hz;
  const auto& s = expert.samples();
  const double t0 = s.front().t_s;
  const auto count = static_cast<std::size_t>(std::floor((s.back().t_s - t0) / dt_s_)) + 1;
  points_.resize(count);
  std::size_t k = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const double t = t0 + static_cast<double>(i) * dt_s_;
    while (k + 2 < s.size() && s[k + 1].t_s <= t) ++k;
    const Sample& a = s[k];
    const Sample& b = s[k + 1];
    const double w = std::clamp((t - a.t_s) / (b.t_s - a.t_s), 0.0, 1.0);
    points_[i] = {(1 - w) * a.p_WT + w * b.p_WT, (1 - w) * a.v_WT + w * b.v_WT, (1 - w) * a.f_user_W + w * b.f_user_W,
                  w < 0.5 ? a.pen_down : b.pen_down};
  }
}

ReferencePoint ReferenceTrajectory::at(double index) const noexcept {
  const double clamped = std::clamp(index, 0.0, static_cast<double>(points_.size() - 1));
  const auto i = std::min(static_cast<std::size_t>(clamped), points_.size() - 2);
  const double w = clamped - static_cast<double>(i);
  const ReferencePoint& a = points_[i];
  const ReferencePoint& b = points_[i + 1];
  return {(1 - w) * a.p_WT + w * b.p_WT, (1 - w) * a.v_WT + w * b.v_WT, (1 - w) * a.f_W + w * b.f_W,
          w < 0.5 ? a.pen_down : b.pen_down};
}

Indexing parseIndexing(std::string_view text) {
  if (text == "time") return Indexing::kTime;
  if (text == "progress") return Indexing::kProgress;
  throw InputError(fmt::format("indexing: expected time or progress, got \"{}\"", text));
}

std::string_view indexingName(Indexing indexing) { return indexing == Indexing::kTime ? "time" : "progress"; }

ReferencePlayer::ReferencePlayer(const ReferenceTrajectory& trajectory, const PlaybackConfig& config)
    : trajectory_(trajectory), config_(config) {
  HATTR_THROW_UNLESS(std::isfinite(config.speed) && config.speed > 0.0 && config.speed <= 10.0,
                     "playback speed: expected a number in (0, 10], got {}", config.speed);
  HATTR_THROW_UNLESS(config.end_hold_s >= 0.0 && config.fade_out_s >= 0.0,
                     "playback: end hold and fade-out must be >= 0 s, got {} and {}", config.end_hold_s, config.fade_out_s);
  HATTR_THROW_UNLESS(config.progress_window >= 1, "playback: progress window: expected >= 1 sample, got 0");
}

void ReferencePlayer::restart() noexcept {
  progress_index_ = 0;
  end_reached_s_ = -1.0;
}

ReferenceCue ReferencePlayer::at(double t_trial_s, const Vec3& p_WT) noexcept {
  ReferenceCue cue;
  const double last = static_cast<double>(trajectory_.size() - 1);
  if (t_trial_s < 0.0) {
    cue.point = trajectory_[0];
    return cue;  // before the start: hold the first point
  }

  // Where in the reference: by the clock, or by the trainee's progress along the path
  // (nearest point within a window ahead, never behind).
  if (config_.indexing == Indexing::kTime) {
    cue.index = std::min(t_trial_s * config_.speed / trajectory_.dt_s(), last);
  } else {
    const std::size_t end = std::min(progress_index_ + config_.progress_window, trajectory_.size() - 1);
    double best = (trajectory_[progress_index_].p_WT - p_WT).head<2>().squaredNorm();
    for (std::size_t i = progress_index_ + 1; i <= end; ++i) {
      const double d = (trajectory_[i].p_WT - p_WT).head<2>().squaredNorm();
      if (d < best) {
        best = d;
        progress_index_ = i;
      }
    }
    cue.index = static_cast<double>(progress_index_);
  }
  cue.point = trajectory_.at(cue.index);

  // After the end: hold, then fade out. By the clock the reference ends at duration/speed;
  // by progress, when the trainee reaches its last point.
  const bool ended = config_.indexing == Indexing::kTime ? t_trial_s * config_.speed > trajectory_.duration_s()
                                                          : cue.index >= last;
  if (ended) {
    if (end_reached_s_ < 0.0) {
      end_reached_s_ = config_.indexing == Indexing::kTime ? trajectory_.duration_s() / config_.speed : t_trial_s;
    }
    const double since = t_trial_s - end_reached_s_ - config_.end_hold_s;
    cue.phase = ReferenceCue::Phase::kAfter;
    cue.weight = since <= 0.0 ? 1.0 : config_.fade_out_s > 0.0 ? std::max(0.0, 1.0 - since / config_.fade_out_s) : 0.0;
    cue.point.v_WT.setZero();
  } else {
    cue.phase = ReferenceCue::Phase::kRunning;
  }
  return cue;
}

}  // namespace hattr::guidance
