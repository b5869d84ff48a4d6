#include "hattr/device/simulated_device.hpp"

#include <cmath>

namespace hattr::device {
namespace {

double quantize(double value, double quantum) noexcept {
  return quantum > 0.0 ? std::round(value / quantum) * quantum : value;
}

}  // namespace

SimulatedDevice::SimulatedDevice(SimulatedPenParams params, HandScript* hand, std::string uri)
    : params_(std::move(params)), hand_(hand), uri_(std::move(uri)), p_WT_(params_.start_position_W) {}

void SimulatedDevice::reset() noexcept {
  p_WT_ = params_.start_position_W;
  v_WT_.setZero();
  command_W_.setZero();
  hand_force_W_.setZero();
  press_N_ = 0.0;
  t_s_ = 0.0;
  last_write_s_ = 0.0;
  if (hand_) hand_->rewind();
}

// Semi-implicit Euler over [t_s_, t_s] in equal sub-steps no longer than max_substep_s.
// The commanded force is held (zero-order hold, like a DAC) until the command times out.
void SimulatedDevice::advanceTo(double t_s) noexcept {
  const double span = t_s - t_s_;
  if (!(span > 0.0)) return;
  const auto steps = static_cast<int>(std::ceil(span / params_.max_substep_s));
  const double h = span / steps;
  // The same in every sub-step: computed once here (the hand's virtual call in the loop keeps
  // the compiler from hoisting them, and each is a division).
  const double tau = params_.hand.press_time_constant_s;
  const double press_share = tau > 0.0 ? std::min(1.0, h / tau) : 1.0;
  const double stop_brake = 1.0 / (1.0 + h * params_.end_stop_damping_N_s_per_m / params_.mass_kg);
  for (int i = 0; i < steps; ++i) {
    const double t = t_s_ + h * (i + 1);
    if (hand_) {
      // The command is read field by field where the hand wrote it; only the last sub-step's is
      // kept (read() reports its pen-down and tilt).
      const HandCommand command = hand_->command(t);
      // Finger force rises and falls with the muscle's time constant.
      const double target = command.pen_down ? command.press_N : 0.0;
      press_N_ += tau > 0.0 ? (target - press_N_) * press_share : target - press_N_;
      hand_force_W_ = handForce(params_.hand, command, press_N_, altitude_sine_.of(command.altitude_rad), p_WT_, v_WT_);
      if (i + 1 == steps) last_hand_ = command;
    } else {
      hand_force_W_.setZero();
    }
    const bool command_alive = t - last_write_s_ <= params_.command_timeout_s;
    const Vec3 device_force = command_alive ? command_W_ : Vec3(Vec3::Zero());
    // The end stops: past a face of the workspace, a spring pushes back and a damper brakes the
    // axis (implicitly: v / (1 + h·c/m)).
    const Vec3 excess = (p_WT_ - params_.limits.workspace_max_m).cwiseMax(0.0) +
                        (p_WT_ - params_.limits.workspace_min_m).cwiseMin(0.0);
    const Vec3 stop_force = -params_.end_stop_stiffness_N_per_m * excess;
    const Vec3 acceleration =
        (device_force + hand_force_W_ + stop_force - params_.damping_N_s_per_m * v_WT_) / params_.mass_kg;
    v_WT_ += h * acceleration;
    for (int axis = 0; axis < 3; ++axis) {
      if (excess[axis] != 0.0) v_WT_[axis] *= stop_brake;
    }
    p_WT_ += h * v_WT_;
  }
  t_s_ = t_s;
}

DeviceStatus SimulatedDevice::read(std::chrono::nanoseconds now, PenState& out) noexcept {
  advanceTo(std::chrono::duration<double>(now).count());
  const double q = params_.position_quantum_m;
  out.t_s = t_s_;
  out.p_WT = Vec3(quantize(p_WT_.x(), q), quantize(p_WT_.y(), q), quantize(p_WT_.z(), q));
  out.v_WT = v_WT_;
  out.buttons = last_hand_.pen_down ? 1u : 0u;
  out.has_force = false;
  out.has_pressure = false;
  out.has_tilt = true;
  out.azimuth_rad = last_hand_.azimuth_rad;
  out.altitude_rad = last_hand_.altitude_rad;
  return DeviceStatus::kOk;
}

DeviceStatus SimulatedDevice::write(const Vec3& f_on_pen_W) noexcept {
  last_write_s_ = t_s_;
  if (!f_on_pen_W.allFinite()) {
    command_W_.setZero();
    return DeviceStatus::kFault;
  }
  command_W_ = f_on_pen_W;
  return DeviceStatus::kOk;
}

}  // namespace hattr::device
