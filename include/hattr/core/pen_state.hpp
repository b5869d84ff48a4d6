#pragma once
/// What the servo loop reads from a device once per tick (the world and the guidance compute
/// from it: world_renderer.hpp, guidance_controller.hpp). SI units, frame W
/// (docs/units_and_frames.md).

#include <cstdint>

#include "hattr/core/types.hpp"

namespace hattr {

/// The pen as a device reports it at one tick.
struct PenState {
  double t_s = 0.0;                   ///< loop time of this reading [s]
  Vec3 p_WT = Vec3::Zero();           ///< pen-tip position in W [m]
  Vec3 v_WT = Vec3::Zero();           ///< pen-tip velocity in W [m/s]
  std::uint32_t buttons = 0;          ///< bit 0: the stylus button / pen switch
  bool has_force = false;             ///< f_measured_W is a force-sensor reading
  Vec3 f_measured_W = Vec3::Zero();   ///< force the user applies through the pen [N]
  bool has_pressure = false;          ///< pressure_raw is meaningful
  double pressure_raw = 0.0;          ///< raw axial pressure, device units
  bool has_tilt = false;              ///< azimuth and altitude are meaningful
  double azimuth_rad = 0.0;           ///< clockwise from +y to the barrel's projection [rad]
  double altitude_rad = 0.0;          ///< pen axis above the paper [rad]
};

}  // namespace hattr
