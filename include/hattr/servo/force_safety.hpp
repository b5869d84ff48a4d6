#pragma once
/// The one safety path every force passes before the device (libfranka's limitRate and
/// cancel-on-error, MuJoCo's reset on bad numbers): reject non-finite values (latch a fault,
/// zero force), add soft walls at the workspace boundary, clamp the magnitude, ramp in at
/// start and after a fault or stall, limit the rate of change. Servo thread: noexcept, no
/// allocation.

#include <cstdint>

#include "hattr/core/types.hpp"
#include "hattr/device/device.hpp"

namespace hattr::servo {

struct SafetyConfig {
  double max_force_N = 0.0;              ///< magnitude clamp; 0: the device's continuous force
  double max_rate_N_per_s = 2000.0;      ///< largest change of the force per second
  double ramp_time_s = 0.25;             ///< forces fade in over this time after start / a fault
  double wall_margin_m = 0.005;          ///< soft walls start this far inside the workspace box
  double wall_stiffness_N_per_m = 400.0; ///< soft-wall stiffness
};

enum class SafetyFault : std::uint8_t { kNone, kNonFiniteForce, kDeviceError };

class ForceSafety {
 public:
  /// Throws InputError for negative or non-finite settings (setup time only).
  ForceSafety(const SafetyConfig& config, const device::DeviceLimits& limits);

  /// The force to send to the device for the world's (the paper's) force and the guidance
  /// force at pen position p_WT. When their sum exceeds the limit, the guidance gives way
  /// first: the paper keeps supporting the pen as far as the limit allows.
  Vec3 filter(const Vec3& world_W, const Vec3& guidance_W, const Vec3& p_WT, double dt_s) noexcept;
  /// The same for a single force.
  Vec3 filter(const Vec3& requested_W, const Vec3& p_WT, double dt_s) noexcept {
    return filter(requested_W, Vec3::Zero(), p_WT, dt_s);
  }
  /// Latches a fault: zero force until clearFault().
  void latchFault(SafetyFault fault) noexcept;
  /// Clears a latched fault; forces ramp in again.
  void clearFault() noexcept;
  /// Zero force now and ramp in again (start, stall, mode change).
  void restartRamp() noexcept;

  [[nodiscard]] SafetyFault fault() const noexcept { return fault_; }
  [[nodiscard]] std::uint64_t faultCount() const noexcept { return faults_; }
  [[nodiscard]] std::uint64_t clampCount() const noexcept { return clamps_; }
  [[nodiscard]] double maxForce_N() const noexcept { return max_force_N_; }
  [[nodiscard]] double rampLevel() const noexcept { return ramp_; }

 private:
  Vec3 softWallForce(const Vec3& p_WT) const noexcept;

  SafetyConfig config_;
  Vec3 wall_min_m_;
  Vec3 wall_max_m_;
  double max_force_N_;
  double ramp_ = 0.0;
  Vec3 last_W_ = Vec3::Zero();
  SafetyFault fault_ = SafetyFault::kNone;
  std::uint64_t faults_ = 0;
  std::uint64_t clamps_ = 0;
};

}  // namespace hattr::servo
