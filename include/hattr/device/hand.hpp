#pragma once
/// The simulated hand that holds the simulated pen: an impedance that pulls the pen toward
/// a target and presses it along its axis with an intended force. Where the target comes
/// from is a HandScript: a profile file, a simulated trainee, or the mouse in the studio.

#include <cstddef>

#include "hattr/core/hand_command.hpp"
#include "hattr/core/haptic_profile.hpp"
#include "hattr/core/pen_state.hpp"
#include "hattr/core/sine_memo.hpp"

namespace hattr::device {

/// What the hand wants at one instant (declared in core so the wire protocol can carry it).
using HandCommand = hattr::HandCommand;

/// A source of hand commands. command() is called on the servo thread (through the
/// simulated device): noexcept, no allocation.
class HandScript {
 public:
  virtual ~HandScript() = default;
  /// The command at loop time t_s; calls come with non-decreasing t_s within a run.
  virtual HandCommand command(double t_s) noexcept = 0;
  /// Back to the start (before a new run). Not on the servo thread.
  virtual void rewind() noexcept {}
};

/// The hand's mechanical impedance. Defaults: a relaxed grip on a pen; see docs/realtime.md.
struct HandImpedance {
  double stiffness_N_per_m = 300.0;
  double damping_N_s_per_m = 4.0;
  /// The pressing force follows its command through a first-order lag (muscle activation
  /// dynamics: finger force cannot step). 0: no lag.
  double press_time_constant_s = 0.04;
  /// The most the hand pushes the pen with, in any direction [N]: a firm grip, well under an
  /// adult's tip-pinch strength (about 50 N). A script asking for more gets this much.
  double max_force_N = 20.0;
  /// The writer's hand rests on the paper, so the fingers reach only so far under its surface
  /// (HandCommand::surface_z_m; z = 0 on flat paper): the press eases off linearly from
  /// `press_ease_begin_m` under it to nothing at `press_ease_end_m`, and deeper the fingers hold
  /// the pen back with the hand's stiffness. A pen that gives way under the fingers is not chased
  /// through the desk.
  double press_ease_begin_m = 0.004;
  double press_ease_end_m = 0.012;
};

/// Force the hand exerts on the pen for a command and the pen's state [N, W].
Vec3 handForce(const HandImpedance& hand, const HandCommand& command, const Vec3& p_WT, const Vec3& v_WT) noexcept;
/// The same with the press the fingers give now (`press_N`, in place of command.press_N: a hand
/// whose press lags its command) and sin(command.altitude_rad) (a caller that remembers it:
/// SineMemo).
Vec3 handForce(const HandImpedance& hand, const HandCommand& command, double press_N, double sin_altitude,
               const Vec3& p_WT, const Vec3& v_WT) noexcept;

/// A hand that holds still at a point, pressing with a constant force.
class StillHand final : public HandScript {
 public:
  explicit StillHand(HandCommand command) : command_(command) {}
  HandCommand command(double) noexcept override { return command_; }

 private:
  HandCommand command_;
};

/// A hand writing circles on the paper: centre, radius, turns per second, pressing with a
/// constant axial force at a fixed tilt. Used by servo-check, the benchmarks and tests.
class CircleHand final : public HandScript {
 public:
  CircleHand(Vec3 centre_W, double radius_m, double turns_per_s, double press_N)
      : centre_W_(centre_W), radius_m_(radius_m), omega_(2.0 * 3.141592653589793 * turns_per_s), press_N_(press_N) {}
  HandCommand command(double t_s) noexcept override;

 private:
  Vec3 centre_W_;
  double radius_m_;
  double omega_;
  double press_N_;
};

/// How a ProfileHandScript plays its profile beyond the path and the press force.
struct ProfilePlayback {
  double grip = 1.0;           ///< HandCommand::grip of every command
  bool push_in_plane = false;  ///< push with the profile's in-plane f_user_W (interpolated)
};

/// Plays a recorded haptic profile as the hand's target: the position and velocity at the
/// time (linearly interpolated), the press force that reproduces the profile's normal force
/// at its tilt (or at `default_altitude_rad`), pen-down as recorded. Holds the last sample
/// after the end. `start_offset_W` shifts the path. `playback`: the grip and, if asked, the
/// profile's in-plane force as the hand's push (a force plan; see sim::SimulatedTrainee).
class ProfileHandScript final : public HandScript {
 public:
  explicit ProfileHandScript(const HapticProfile& profile, double default_altitude_rad = 1.0471975511965976,
                             Vec3 start_offset_W = Vec3::Zero(), ProfilePlayback playback = {});
  HandCommand command(double t_s) noexcept override;
  void rewind() noexcept override { cursor_ = 0; }
  [[nodiscard]] double duration_s() const noexcept;

 private:
  std::vector<Sample> samples_;
  bool has_tilt_;
  double default_altitude_rad_;
  Vec3 offset_W_;
  ProfilePlayback playback_;
  std::size_t cursor_ = 0;
  SineMemo altitude_sine_;
};

}  // namespace hattr::device
