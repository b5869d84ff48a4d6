#pragma once
/// The device layer: a force-feedback pen (or a tablet, or a remote partner) as the servo
/// loop sees it. read() and write() run on the servo thread: noexcept, no allocation, no
/// locks, no I/O beyond the device's own transport.

#include <chrono>
#include <string>

#include "hattr/core/device_limits.hpp"
#include "hattr/core/pen_state.hpp"

namespace hattr::device {

/// What a device can do (declared in core so render and guidance can use it).
using DeviceLimits = hattr::DeviceLimits;

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
