#pragma once
/// The simulated planar pen, sim://planar: the open pen's plant (device::PlanarPlant: the reference
/// build's motors, five-bar, table and the simulated hand) driven directly, without firmware,
/// encoders, PWM steps or ADC: what the open pen would be with ideal electronics. It reads and
/// writes as the serial:// device does (the same conventions: the sensor's normal force as
/// pressure_raw [N], the tip 1 mm up when the press is under contact_N, forces through the
/// Jacobian transpose as motor efforts), so a trial on it and the same trial on the emulated
/// firmware differ only by what the electronics and the link add (docs/BENCHMARKS.md).

#include <string>

#include "hattr/device/device.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/device/planar_pen.hpp"

namespace hattr::device {

class SimulatedPlanarDevice final : public Device {
 public:
  /// `hand` may be null (nobody holds the pen) and must outlive the device.
  SimulatedPlanarDevice(const PlanarPlantParams& params, HandScript* hand, std::string uri = "sim://planar");

  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override;
  DeviceStatus write(const Vec3& f_on_pen_W) noexcept override;
  const DeviceLimits& limits() const noexcept override { return limits_; }
  DeviceCapabilities capabilities() const noexcept override { return {.pressure = true}; }
  const std::string& uri() const noexcept override { return uri_; }
  DeviceClocking clocking() const noexcept override { return DeviceClocking::kSimulatable; }

  [[nodiscard]] const PlanarPlant& plant() const noexcept { return plant_; }

 private:
  PlanarPlant plant_;
  HandScript* hand_;
  std::string uri_;
  DeviceLimits limits_;
  Vec2 effort_ = Vec2::Zero();   // the last command's efforts (±HPEN_EFFORT_FULL)
  double t_s_ = 0.0;
  double last_write_s_ = 0.0;
};

/// The plant's parameters for a sim://planar URI (no keys yet: any key is refused).
PlanarPlantParams simulatedPlanarParams(const DeviceUri& uri);

}  // namespace hattr::device
