#pragma once
/// One servo-rate sample of a haptic profile. Fixed size and copied without allocating or
/// throwing, so the servo loop can push it through lock-free rings. SI units, frame W (docs/units_and_frames.md).

#include <cstdint>

#include "hattr/core/types.hpp"

namespace hattr {

struct Sample {
  double t_s = 0.0;                     ///< time since the profile started [s]
  Vec3 p_WT = Vec3::Zero();             ///< pen-tip position T in W [m]
  Vec3 v_WT = Vec3::Zero();             ///< pen-tip velocity in W [m/s]
  Vec3 f_user_W = Vec3::Zero();         ///< force the pen (the user) exerts on the paper, in W [N]
  Vec3 f_cmd_W = Vec3::Zero();          ///< total force the device commands on the pen, in W [N]
  Vec3 f_guide_W = Vec3::Zero();        ///< guidance (assistance) part of f_cmd_W [N]
  bool in_contact = false;              ///< the pen tip touches the paper
  bool pen_down = false;                ///< the pen is down (button, or contact on a haptic pen)
  double pressure_raw = 0.0;            ///< raw axial pressure, device units (if the profile has it)
  double tilt_azimuth_rad = 0.0;        ///< pen azimuth [rad] (if the profile has tilt)
  double tilt_altitude_rad = 0.0;       ///< pen altitude above the paper [rad] (if it has tilt)
};

}  // namespace hattr

namespace hattr {

/// A sample as the servo loop publishes it: with the number of the tick that made it, so a
/// consumer can tell a lost sample (a gap in the numbers) from a late tick (a gap in time).
struct TickSample {
  std::uint64_t tick = 0;
  Sample sample;
};

/// Exact equality of every field (the round-trip tests rely on it).
inline bool operator==(const Sample& a, const Sample& b) {
  return a.t_s == b.t_s && a.p_WT == b.p_WT && a.v_WT == b.v_WT && a.f_user_W == b.f_user_W &&
         a.f_cmd_W == b.f_cmd_W && a.f_guide_W == b.f_guide_W && a.in_contact == b.in_contact &&
         a.pen_down == b.pen_down && a.pressure_raw == b.pressure_raw &&
         a.tilt_azimuth_rad == b.tilt_azimuth_rad && a.tilt_altitude_rad == b.tilt_altitude_rad;
}

}  // namespace hattr
