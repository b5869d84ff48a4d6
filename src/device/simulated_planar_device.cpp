#include "hattr/device/simulated_planar_device.hpp"

#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/openpen/protocol.h"

namespace hattr::device {
PlanarPlantParams simulatedPlanarParams(const DeviceUri& uri) {
  HATTR_THROW_UNLESS(uri.query.empty(), "sim://planar: unknown key \"{}\": the simulated planar pen takes no keys",
                     uri.query.begin()->first);
  return {};
}

SimulatedPlanarDevice::SimulatedPlanarDevice(const PlanarPlantParams& params, HandScript* hand, std::string uri)
    : plant_(params), hand_(hand), uri_(std::move(uri)), limits_(planarPenLimits(params.spec)) {}

// The plant up to `now` in its own steps, under the last efforts (zero after the pen's watchdog
// time without a write, as the firmware does).
DeviceStatus SimulatedPlanarDevice::read(std::chrono::nanoseconds now, PenState& out) noexcept {
  const double target_s = std::chrono::duration<double>(now).count();
  const PlanarPenSpec& spec = plant_.params().spec;
  constexpr double kStep_s = 1e-4;
  while (t_s_ < target_s - 1e-12) {
    const double dt = std::min(kStep_s, target_s - t_s_);
    const bool alive = t_s_ - last_write_s_ < spec.watchdog_s;
    const Vec2 duty = alive ? Vec2(effort_ / HPEN_EFFORT_FULL) : Vec2::Zero();
    const std::array<bool, 2> driven{alive && effort_[0] != 0.0, alive && effort_[1] != 0.0};
    HandCommand command;
    if (hand_ != nullptr) command = hand_->command(t_s_);
    plant_.step(dt, duty, driven, hand_ != nullptr ? &command : nullptr);
    t_s_ += dt;
  }
  out = PenState{};
  out.t_s = target_s;
  out.p_WT = plant_.penPosition();
  out.v_WT = plant_.penVelocity();
  const double press_N = plant_.normalForce_N();
  out.p_WT.z() = planarTipHeight(press_N, kPlanarContact_N);
  out.has_pressure = true;
  out.pressure_raw = press_N;
  return DeviceStatus::kOk;
}

DeviceStatus SimulatedPlanarDevice::write(const Vec3& f_on_pen_W) noexcept {
  const Vec3 f = f_on_pen_W.allFinite() ? f_on_pen_W : Vec3::Zero();
  // The efforts the firmware would get; the plant takes them as duty in each motor's own sense.
  const auto efforts = motorEfforts(plant_.params().spec, jointTorques(plant_.params().spec, plant_.q(), f));
  effort_ = Vec2(efforts[0], efforts[1]);
  last_write_s_ = t_s_;
  return DeviceStatus::kOk;
}

}  // namespace hattr::device
