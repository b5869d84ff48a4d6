#pragma once
/// The device layer: a force-feedback pen (or a tablet, or a remote partner) as the servo
/// loop sees it. read() and write() run on the servo thread: noexcept, no allocation, no
/// locks, no I/O beyond the device's own transport.

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

#include "hattr/core/device_limits.hpp"
#include "hattr/core/pen_state.hpp"
#include "hattr/device/link_stats.hpp"

namespace hattr::device {

/// What a device can do, what it measures, how it is (declared in core so render, guidance
/// and the wire protocol can use them).
using DeviceLimits = hattr::DeviceLimits;
using DeviceCapabilities = hattr::DeviceCapabilities;
using DeviceStatus = hattr::DeviceStatus;

/// Who runs the servo loop's clock for a device (ServoLoop::start picks from this).
enum class DeviceClocking {
  kSimulatable,   ///< the loop's own clock: simulated time or a real-time thread (sim://pen)
  kHostRealTime,  ///< the loop's real-time thread only (hardware polled by the host, udp://)
  kDeviceClock,   ///< the device calls the tick from its own thread at its rate (HD scheduler)
};

/// The tick a device-clocked device calls, once per servo period, from its own thread.
/// `now` is the device's time since startClock(). Must not be called after stopClock().
using DeviceTickFn = void (*)(void* context, std::chrono::nanoseconds now) noexcept;

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

  /// Which clock must run the loop. Default: the loop's real-time thread.
  [[nodiscard]] virtual DeviceClocking clocking() const noexcept { return DeviceClocking::kHostRealTime; }
  /// Device clock only: start calling `tick(context, now)` once per period from the device's
  /// own thread; stopClock() returns once no call is running and none will follow. Throws
  /// hattr::Error if the clock cannot start. Not on the servo thread.
  virtual void startClock(DeviceTickFn tick, void* context);
  virtual void stopClock() noexcept {}
  /// Device clock only: the device's clock is simulated time that may pause in wall time (an
  /// emulator in lockstep, serial://...?lockstep=1). The loop and the trial then judge it by its
  /// own time only: no wall-clock stall count, no force zeroed for a consumer's lag in loop time
  /// (the sample ring holds it), a generous give-up time. Never for real hardware.
  [[nodiscard]] virtual bool pausableClock() const noexcept { return false; }
  /// Why the device last reported kFault or kDisconnected, for messages ("" if it has not).
  /// Not on the servo thread; safe to call while the loop runs.
  [[nodiscard]] virtual std::string faultReason() const { return {}; }
  /// A device behind a network link: what the link did so far and the far end's rate; none for
  /// a device that is not. Not on the servo thread; its histograms only while the loop is stopped.
  [[nodiscard]] virtual std::optional<DeviceLink> link() const { return std::nullopt; }
};

/// Checks the limits a device reports about itself (a driver plugin, a device server) as input:
/// finite positive forces, stiffness, rate and mass, non-negative damping, continuous <= peak
/// force, a workspace box with min < max. Throws InputError starting with `who` ("plugin:/x.so:
/// the device", "udp://H:P: the device server").
void checkReportedLimits(const DeviceLimits& limits, std::string_view who);

}  // namespace hattr::device
