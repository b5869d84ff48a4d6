#include "hattr/device/hand.hpp"

#include <algorithm>
#include <cmath>

#include "hattr/core/error.hpp"

namespace hattr::device {
namespace {

/// The hand lifts the pen at least this high when the script says pen up [m].
constexpr double kLiftHeight_m = 0.003;

}  // namespace

Vec3 handForce(const HandImpedance& hand, const HandCommand& command, const Vec3& p_WT, const Vec3& v_WT) noexcept {
  return handForce(hand, command, command.press_N, std::sin(command.altitude_rad), p_WT, v_WT);
}

Vec3 handForce(const HandImpedance& hand, const HandCommand& command, double press_N, double sin_altitude,
               const Vec3& p_WT, const Vec3& v_WT) noexcept {
  Vec3 force = hand.stiffness_N_per_m * (command.p_target_W - p_WT) +
               hand.damping_N_s_per_m * (command.v_target_W - v_WT);
  // In the paper plane: the grip's share of the impedance, and the feedforward push.
  force.head<2>() = command.grip * force.head<2>() + command.push_W.head<2>();
  if (command.pen_down) {
    // Writing: the fingers steer the tip in the paper plane and press it into the paper
    // with the normal share F·sin θ of the axial force (the tangential share is carried
    // by the grip). The hand does not hold the height, but the fingers still damp it.
    // The fingers reach only so far under the paper's surface (the hand rests on the paper):
    // deeper, the press eases off, and past the reach the fingers hold the pen back.
    const double depth_m = command.surface_z_m - p_WT.z();
    const double reach = std::clamp((hand.press_ease_end_m - depth_m) / (hand.press_ease_end_m - hand.press_ease_begin_m),
                                    0.0, 1.0);
    const double held_back_N = hand.stiffness_N_per_m * std::max(depth_m - hand.press_ease_end_m, 0.0);
    force.z() = -std::max(press_N, 0.0) * reach * sin_altitude + held_back_N -
                hand.damping_N_s_per_m * v_WT.z();
  }
  // No hand pushes harder than a firm grip (a stale or far target does not make it 100 N). The
  // square root only near the grip's limit: well under it (by far more than rounding), the
  // magnitude cannot exceed it, and the square root is most of a sub-step's wait.
  const double squared = force.squaredNorm();
  if (squared > 0.99 * hand.max_force_N * hand.max_force_N) {
    const double magnitude = std::sqrt(squared);
    if (magnitude > hand.max_force_N) force *= hand.max_force_N / magnitude;
  }
  return force;
}

HandCommand CircleHand::command(double t_s) noexcept {
  const double angle = omega_ * t_s;
  HandCommand cmd;
  cmd.p_target_W = centre_W_ + radius_m_ * Vec3(std::cos(angle), std::sin(angle), 0.0);
  cmd.v_target_W = radius_m_ * omega_ * Vec3(-std::sin(angle), std::cos(angle), 0.0);
  cmd.press_N = press_N_;
  cmd.azimuth_rad = 2.356194490192345;  // barrel toward the writer's lower right (135°)
  cmd.pen_down = true;
  return cmd;
}

ProfileHandScript::ProfileHandScript(const HapticProfile& profile, double default_altitude_rad, Vec3 start_offset_W,
                                     ProfilePlayback playback)
    : samples_(profile.samples()),
      has_tilt_(profile.rawChannels().tilt),
      default_altitude_rad_(default_altitude_rad),
      offset_W_(start_offset_W),
      playback_(playback) {
  HATTR_THROW_UNLESS(!samples_.empty(), "hand script: the profile has no samples");
  HATTR_THROW_UNLESS(std::isfinite(playback.grip) && playback.grip > 0.0 && playback.grip <= 1.0,
                     "hand script: grip: expected a share in (0, 1], got {}", playback.grip);
}

double ProfileHandScript::duration_s() const noexcept { return samples_.back().t_s - samples_.front().t_s; }

HandCommand ProfileHandScript::command(double t_s) noexcept {
  // Find the samples around the time (the cursor only moves forward within a run).
  const double t = t_s + samples_.front().t_s;
  while (cursor_ + 1 < samples_.size() && samples_[cursor_ + 1].t_s <= t) ++cursor_;
  const Sample& a = samples_[cursor_];
  const Sample& b = samples_[std::min(cursor_ + 1, samples_.size() - 1)];
  const double span = b.t_s - a.t_s;
  const double w = span > 0.0 ? std::clamp((t - a.t_s) / span, 0.0, 1.0) : 0.0;

  HandCommand cmd;
  cmd.p_target_W = (1.0 - w) * a.p_WT + w * b.p_WT + offset_W_;
  cmd.v_target_W = t < samples_.back().t_s ? Vec3((1.0 - w) * a.v_WT + w * b.v_WT) : Vec3(Vec3::Zero());
  cmd.pen_down = w < 0.5 ? a.pen_down : b.pen_down;
  cmd.azimuth_rad = has_tilt_ ? a.tilt_azimuth_rad : 0.0;
  cmd.altitude_rad = has_tilt_ ? std::clamp(a.tilt_altitude_rad, 0.1, 1.5707963267948966) : default_altitude_rad_;
  // The axial force that gives the recorded normal force at this tilt.
  const double normal_N = -((1.0 - w) * a.f_user_W.z() + w * b.f_user_W.z());
  cmd.press_N = cmd.pen_down ? std::max(normal_N, 0.0) / altitude_sine_.of(cmd.altitude_rad) : 0.0;
  if (!cmd.pen_down) cmd.p_target_W.z() = std::max(cmd.p_target_W.z(), kLiftHeight_m);
  cmd.grip = playback_.grip;
  if (playback_.push_in_plane) {
    const Vec3 f = (1.0 - w) * a.f_user_W + w * b.f_user_W;
    cmd.push_W = Vec3(f.x(), f.y(), 0.0);
  }
  return cmd;
}

}  // namespace hattr::device
