#pragma once
/// The device layer: a force-feedback pen (or a tablet, or a remote partner) as the servo
/// loop sees it. read() and write() run on the servo thread: noexcept, no allocation, no
/// locks, no I/O beyond the device's own transport.

#include <chrono>
#include <string>

#include "hattr/core/pen_state.hpp"

namespace hattr::device {

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
};

/// What a device measures besides position and velocity.
struct DeviceCapabilities {
  bool force_sensor = false;
  bool pressure = false;
  bool tilt = false;
};

enum class DeviceStatus { kOk, kFault, kDisconnected };

class Device {
 public:
  virtual ~Device() = default;
  /// Reads the pen at loop time `now` (since the loop started). Servo thread only.
  [[nodiscard]] virtual DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept = 0;
  /// Commands the force on the pen until the next write [N, W]. Servo thread only.
  [[nodiscard]] virtual DeviceStatus write(const Vec3& f_on_pen_W) noexcept = 0;
  [[nodiscard]] virtual const DeviceLimits& limits() const noexcept = 0;
  [[nodiscard]] virtual DeviceCapabilities capabilities() const noexcept = 0;
  /// The URI the device was opened with (for metadata).
  [[nodiscard]] virtual const std::string& uri() const noexcept = 0;
};

}  // namespace hattr::device
