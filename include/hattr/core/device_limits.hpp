#pragma once
/// What a device can do and how it is, declared once by each device (see
/// hattr::device::Device). Plain data in core, so the renderer and the guidance can check
/// their gains against it and the wire protocol can carry it. SI.

#include "hattr/core/types.hpp"

namespace hattr {

/// What a device can do, declared once. SI units.
struct DeviceLimits {
  int degrees_of_freedom = 3;                           ///< actuated translational DOF
  Vec3 workspace_min_m = Vec3(-0.08, -0.06, -0.06);     ///< workspace box in W [m]
  Vec3 workspace_max_m = Vec3(0.08, 0.06, 0.06);
  double peak_force_N = 7.9;                            ///< short-term maximum [N]
  double continuous_force_N = 1.75;                     ///< sustainable force [N]
  double max_stiffness_N_per_m = 1000.0;                ///< largest stiffness rendered stably at its rate
  double max_damping_N_s_per_m = 5.0;                   ///< largest damping rendered stably at its rate
  double nominal_rate_hz = 1000.0;                      ///< the servo rate it is specified for
  double mass_kg = 0.045;                               ///< apparent mass at the tip (for passivity bounds)
  double damping_N_s_per_m = 1.0;                       ///< physical damping (for passivity bounds)
  /// Every field equal, to the bit.
  friend bool operator==(const DeviceLimits&, const DeviceLimits&) = default;
};

/// What a device measures besides position and velocity.
struct DeviceCapabilities {
  bool force_sensor = false;
  bool pressure = false;
  bool tilt = false;
  friend bool operator==(const DeviceCapabilities&, const DeviceCapabilities&) = default;
};

/// How a device is at one read.
enum class DeviceStatus { kOk, kFault, kDisconnected };

}  // namespace hattr
