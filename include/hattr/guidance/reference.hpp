#pragma once
/// The expert's haptic profile as a reference the servo thread plays: resampled to the servo
/// rate, indexed by time (the paper's way: the reference at the time since the trial began,
/// times a speed factor) or by progress (beyond the paper: the reference point follows the
/// trainee along the path, searched forward only). See docs/training_modes.md.

#include <cstddef>
#include <string_view>
#include <vector>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::guidance {

/// One point of the reference. SI, frame W.
struct ReferencePoint {
  Vec3 p_WT = Vec3::Zero();   ///< the expert's pen-tip position [m]
  Vec3 v_WT = Vec3::Zero();   ///< the expert's velocity [m/s]
  Vec3 f_W = Vec3::Zero();    ///< the force the expert exerted on the paper [N]
  bool pen_down = false;
};

class ReferenceTrajectory {
 public:
  /// Resamples `expert` onto a uniform grid at `rate_hz` starting at its first sample
  /// (linear interpolation; pen-down from the nearer sample). Throws InputError for fewer
  /// than two samples or a rate outside 1–10 kHz. Not for the servo thread.
  ReferenceTrajectory(const HapticProfile& expert, double rate_hz);

  [[nodiscard]] std::size_t size() const noexcept { return points_.size(); }
  [[nodiscard]] const ReferencePoint& operator[](std::size_t i) const noexcept { return points_[i]; }
  [[nodiscard]] double dt_s() const noexcept { return dt_s_; }
  [[nodiscard]] double duration_s() const noexcept { return dt_s_ * static_cast<double>(points_.size() - 1); }
  /// The reference at a fractional index (linear interpolation, clamped to the ends).
  [[nodiscard]] ReferencePoint at(double index) const noexcept;

 private:
  double dt_s_;
  std::vector<ReferencePoint> points_;
};

enum class Indexing { kTime, kProgress };
/// "time" or "progress"; throws InputError otherwise.
Indexing parseIndexing(std::string_view text);
std::string_view indexingName(Indexing indexing);

struct PlaybackConfig {
  Indexing indexing = Indexing::kTime;
  double speed = 1.0;                 ///< reference seconds per trial second (time indexing)
  double end_hold_s = 0.2;            ///< after the end: hold the last point this long...
  double fade_out_s = 0.3;            ///< ...then fade the guidance out over this long
  std::size_t progress_window = 50;   ///< progress indexing: samples searched ahead per tick
};

/// Where in the reference the trial is.
struct ReferenceCue {
  enum class Phase { kBefore, kRunning, kAfter };
  ReferencePoint point;
  double index = 0.0;      ///< fractional index into the trajectory
  double weight = 1.0;     ///< 1 while playing; falls to 0 over fade_out_s after the end
  Phase phase = Phase::kBefore;
};

/// Plays a trajectory on the servo thread: noexcept, no allocation.
class ReferencePlayer {
 public:
  /// `trajectory` must outlive the player.
  ReferencePlayer(const ReferenceTrajectory& trajectory, const PlaybackConfig& config);
  /// Back to the start (a new trial).
  void restart() noexcept;
  /// The cue at `t_trial_s` since the trial started, for the pen at `p_WT`. Calls within a
  /// trial come with non-decreasing times.
  ReferenceCue at(double t_trial_s, const Vec3& p_WT) noexcept;
  [[nodiscard]] const PlaybackConfig& config() const noexcept { return config_; }

 private:
  const ReferenceTrajectory& trajectory_;
  PlaybackConfig config_;
  std::size_t progress_index_ = 0;
  double end_reached_s_ = -1.0;
};

}  // namespace hattr::guidance
