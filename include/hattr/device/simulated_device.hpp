#pragma once
/// A simulated force-feedback pen: a point mass with viscous damping in 3-D, integrated
/// with semi-implicit Euler in sub-steps of at most `max_substep_s`, driven by the device's
/// commanded force and by a simulated hand, and held inside its workspace by end stops. It is
/// the test double for every hardware test and the device of every simulated study. Default
/// parameters: docs/realtime.md.

#include <chrono>
#include <string>

#include "hattr/device/device.hpp"
#include "hattr/device/hand.hpp"

namespace hattr::device {

struct SimulatedPenParams {
  double mass_kg = 0.045;                 ///< apparent mass at the tip
  double damping_N_s_per_m = 1.0;         ///< viscous damping of the mechanism
  double position_quantum_m = 0.0;        ///< encoder resolution (0: none)
  double max_substep_s = 2.5e-4;          ///< integration sub-step bound
  double command_timeout_s = 0.010;       ///< the commanded force drops to zero without a write for this long
  Vec3 start_position_W = Vec3(0.0, 0.0, 0.005);  ///< where the pen starts [m]
  /// The mechanism's end stops at each face of the workspace box (limits.workspace_*): a stiff
  /// wall, damped (implicitly, so any mass stays stable), as a real linkage's hard stops.
  double end_stop_stiffness_N_per_m = 20000.0;
  double end_stop_damping_N_s_per_m = 40.0;
  HandImpedance hand;
  DeviceLimits limits;
};

class SimulatedDevice final : public Device {
 public:
  /// `hand` may be null (nobody holds the pen) and must outlive the device.
  SimulatedDevice(SimulatedPenParams params, HandScript* hand, std::string uri = "sim://pen");

  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override;
  DeviceStatus write(const Vec3& f_on_pen_W) noexcept override;
  const DeviceLimits& limits() const noexcept override { return params_.limits; }
  DeviceCapabilities capabilities() const noexcept override { return {.tilt = true}; }
  const std::string& uri() const noexcept override { return uri_; }
  DeviceClocking clocking() const noexcept override { return DeviceClocking::kSimulatable; }

  /// Replaces the hand (null: none). Not while the loop runs.
  void setHand(HandScript* hand) noexcept { hand_ = hand; }
  /// Back to the start position at rest, time 0. Not while the loop runs.
  void reset() noexcept;

  /// The true (unquantized) state, for tests and analysis.
  [[nodiscard]] const Vec3& truePosition() const noexcept { return p_WT_; }
  [[nodiscard]] const Vec3& trueVelocity() const noexcept { return v_WT_; }
  /// The force the device last received (what the hardware would output) [N].
  [[nodiscard]] const Vec3& lastCommand() const noexcept { return command_W_; }
  /// The force the hand exerted at the last sub-step [N].
  [[nodiscard]] const Vec3& lastHandForce() const noexcept { return hand_force_W_; }
  [[nodiscard]] const SimulatedPenParams& params() const noexcept { return params_; }

 private:
  void advanceTo(double t_s) noexcept;

  SimulatedPenParams params_;
  HandScript* hand_;
  std::string uri_;
  Vec3 p_WT_;
  Vec3 v_WT_ = Vec3::Zero();
  Vec3 command_W_ = Vec3::Zero();
  Vec3 hand_force_W_ = Vec3::Zero();
  HandCommand last_hand_{};
  double press_N_ = 0.0;  // the hand's actual press, lagging its command
  SineMemo altitude_sine_;  // sin of the hand's altitude, asked every sub-step
  double t_s_ = 0.0;
  double last_write_s_ = 0.0;
};

}  // namespace hattr::device
