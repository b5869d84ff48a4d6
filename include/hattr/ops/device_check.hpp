#pragma once
/// The device check (`hattr devices check URI`) as one library call, what a lab runs on a new
/// device: open it, its limits and rate, the loop's jitter for a while with nothing rendered, then
/// a gentle upward force the person holding the pen confirms, each figure with its verdict.
///
/// Threads: runDeviceCheck blocks (seconds + 1 to 5 s); it starts the loop's thread and a
/// consumer and joins them; the callbacks run on the calling thread.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "hattr/core/device_limits.hpp"
#include "hattr/core/histogram.hpp"
#include "hattr/device/device.hpp"
#include "hattr/servo/loop_verdict.hpp"
#include "hattr/servo/servo_loop.hpp"

namespace hattr::ops {

/// What the device is, once opened (DeviceCheckOptions::opened shows it before the run).
struct DeviceDescription {
  std::string uri;
  device::DeviceClocking clocking = device::DeviceClocking::kHostRealTime;
  double rate_hz = 0.0;           ///< the rate the check runs at
  DeviceLimits limits;
  DeviceCapabilities capabilities;
};

struct DeviceCheckOptions {
  std::string uri;
  double seconds = 2.0;           ///< the jitter measurement [s], 0.1 to 60
  double force_N = 0.2;           ///< the gentle test force [N]: (0, the continuous force]; up, or on a planar pen away from the writer
  double rate_hz = 0.0;           ///< 0: the device's nominal rate
  /// Once the device is open, before the loop runs (a front end describes it).
  std::function<void(const DeviceDescription&)> opened;
  /// Before the force: says to the person what comes ("Hold the pen lightly: ...").
  std::function<void(const std::string& notice)> announce;
  /// After the force: whether the person felt it; nullopt: nobody answered. Empty: not asked,
  /// and the force test is judged by what was commanded.
  std::function<std::optional<bool>()> confirm;
};

struct DeviceCheckResult {
  DeviceDescription device;
  servo::LoopClock loop_clock = servo::LoopClock::kNone;
  DurationHistogram period_error;
  servo::LoopFigures figures;
  std::string fault_reason;       ///< the device's last fault, if any
  double force_N = 0.0;           ///< the test force asked for
  std::string force_direction;    ///< "up", or "away from the writer" on a planar pen
  double commanded_N = 0.0;       ///< the largest force commanded along that direction while it was held
  double pen_rise_m = 0.0;        ///< how far the pen moved along it by then
  bool force_reached = false;     ///< commanded within 2 % of force_N
  std::optional<bool> confirmed;  ///< the person's answer (nullopt: not asked or no answer)
  servo::LoopJudgement judgement;
  /// No FAIL, the force reached, and the person did not say no.
  [[nodiscard]] bool ok() const noexcept;
  /// {device, clocking, loop_clock, rate_hz, limits, capabilities, period_error_us, ticks,
  /// overruns, faults, link_faults, stalls, fault_reason, force_test {direction, commanded_N, pen_rise_m,
  /// confirmed}, verdicts, verdict, ok}: the schema of `hattr devices check --json`.
  [[nodiscard]] nlohmann::json toJson() const;
};

/// "host (simulatable)", "host" or "device".
std::string_view clockingName(device::DeviceClocking clocking) noexcept;

/// Runs the check. Throws InputError for a bad URI or options (a force past the device's
/// continuous force), hattr::Error when the device cannot be opened.
DeviceCheckResult runDeviceCheck(const DeviceCheckOptions& options);

}  // namespace hattr::ops
