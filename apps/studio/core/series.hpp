#pragma once
/// What the studio draws from samples: the pen's trail on the paper (pen-down strokes) and
/// force series over time (the haptic-profile plot), filled live from the loop's newest
/// samples or at once from a recorded profile. SI units (metres, seconds, newtons); GUI
/// thread only.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::studio {

/// Pen-down strokes in the paper plane [m]. Each stroke is a polyline.
class Trail {
 public:
  /// At most `max_points` points are kept; the oldest strokes go first.
  explicit Trail(std::size_t max_points = 200'000) : max_points_(max_points) {}

  /// Adds the pen's position if it is down; a pen-up ends the current stroke.
  void append(const Sample& sample);
  /// The strokes of `profile` from sample `begin` up to (not including) `end`.
  void assign(const HapticProfile& profile, std::size_t begin = 0, std::size_t end = static_cast<std::size_t>(-1));
  void clear();

  [[nodiscard]] const std::vector<std::vector<Eigen::Vector2d>>& strokes() const noexcept { return strokes_; }
  [[nodiscard]] std::size_t pointCount() const noexcept { return points_; }
  [[nodiscard]] bool empty() const noexcept { return points_ == 0; }

 private:
  std::size_t max_points_;
  std::vector<std::vector<Eigen::Vector2d>> strokes_;
  std::size_t points_ = 0;
  bool pen_was_down_ = false;
};

/// Force over time: fx, fy, fz of the user's force on the paper [N] against t [s].
struct ForceSeries {
  std::vector<double> t_s;
  std::vector<double> fx_N, fy_N, fz_N;

  void append(double t, const Vec3& f_W);
  void clear();
  [[nodiscard]] std::size_t size() const noexcept { return t_s.size(); }
  [[nodiscard]] bool empty() const noexcept { return t_s.empty(); }
  /// The user's force of a profile, with at most `max_points` points (every k-th sample),
  /// times shifted by `t_offset_s`.
  static ForceSeries fromProfile(const HapticProfile& profile, std::size_t max_points = 4000, double t_offset_s = 0.0);
  /// Smallest and largest force over every channel [N]; {0, 0} when empty.
  [[nodiscard]] std::pair<double, double> forceRange() const noexcept;
};

/// Plays a recorded profile back at `speed` times real time. Times are seconds of any
/// monotonic clock the caller keeps.
class Playback {
 public:
  /// The profile to play (must outlive the playback; null: nothing). Stops playing.
  void load(const HapticProfile* profile);
  void play(double now_s);
  void pause(double now_s);
  void rewind();
  [[nodiscard]] bool playing() const noexcept { return playing_; }
  [[nodiscard]] bool loaded() const noexcept { return profile_ != nullptr && !profile_->empty(); }
  /// Profile time at `now_s` [s], clamped to the profile's span.
  [[nodiscard]] double time_s(double now_s) const noexcept;
  /// The index of the last sample at or before profile time t [s] (0 when empty).
  [[nodiscard]] std::size_t indexAt(double t_s) const noexcept;
  /// True once the playback has reached the end.
  [[nodiscard]] bool finished(double now_s) const noexcept;
  [[nodiscard]] const HapticProfile* profile() const noexcept { return profile_; }
  void setSpeed(double speed) noexcept { speed_ = speed > 0.0 ? speed : 1.0; }

 private:
  const HapticProfile* profile_ = nullptr;
  bool playing_ = false;
  double started_at_s_ = 0.0;   // clock time at which profile time 0 would have been
  double paused_at_t_s_ = 0.0;  // profile time while paused
  double speed_ = 1.0;
};

}  // namespace hattr::studio
