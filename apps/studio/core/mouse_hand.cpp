#include "core/mouse_hand.hpp"

#include <algorithm>
#include <cmath>

namespace hattr::studio {
namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr double kMaxSubstep_s = 5e-4;  // filter integration step bound
constexpr double kMaxGap_s = 0.05;      // a longer gap (a paused loop) is not integrated

}  // namespace

double PressScale::afterWheel(double press_N, int angle_delta_eighths) noexcept {
  const double notches = static_cast<double>(angle_delta_eighths) / 120.0;
  const double raw = std::clamp(press_N + notches * kStep_N, kMin_N, kMax_N);
  return std::round(raw / kStep_N) * kStep_N;
}

double PressScale::fromSliderSteps(int steps) noexcept {
  return std::clamp(static_cast<double>(steps) * kStep_N, kMin_N, kMax_N);
}

int PressScale::toSliderSteps(double press_N) noexcept {
  return static_cast<int>(std::lround(std::clamp(press_N, kMin_N, kMax_N) / kStep_N));
}

MouseHand::MouseHand(const Params& params) : params_(params) { buffer_.write(gui_input_); }

void MouseHand::setInput(const MouseInput& input) noexcept {
  gui_input_ = input;
  buffer_.write(input);
}

void MouseHand::rewind() noexcept { started_ = false; }

device::HandCommand MouseHand::command(double t_s) noexcept {
  (void)buffer_.read(current_);  // keeps the last input when nothing new was published
  const double wanted_press = current_.tablet ? current_.tablet_press_N : current_.press_N;
  const double target_press = current_.pen_down ? std::max(wanted_press, 0.0) : 0.0;
  if (!started_) {
    started_ = true;
    x_m_ = current_.x_m;
    y_m_ = current_.y_m;
    vx_ = vy_ = 0.0;
    press_N_ = target_press;
    last_t_s_ = t_s;
  }
  const double dt = std::clamp(t_s - last_t_s_, 0.0, kMaxGap_s);
  last_t_s_ = t_s;

  // Critically damped follower of the cursor: a'' = w²(target − p) − 2w·p'.
  const double w = kTwoPi * params_.follow_hz;
  const int steps = std::max(1, static_cast<int>(std::ceil(dt / kMaxSubstep_s)));
  const double h = dt / steps;
  for (int i = 0; i < steps && h > 0.0; ++i) {
    vx_ += h * (w * w * (current_.x_m - x_m_) - 2.0 * w * vx_);
    vy_ += h * (w * w * (current_.y_m - y_m_) - 2.0 * w * vy_);
    x_m_ += h * vx_;
    y_m_ += h * vy_;
  }
  // The press force lags the button.
  press_N_ += (1.0 - std::exp(-dt / params_.press_time_constant_s)) * (target_press - press_N_);

  device::HandCommand command;
  command.p_target_W = Vec3(x_m_, y_m_, current_.pen_down ? 0.0 : params_.lift_height_m);
  command.v_target_W = Vec3(vx_, vy_, 0.0);
  command.press_N = press_N_;
  command.pen_down = current_.pen_down;
  command.altitude_rad = current_.tablet ? current_.altitude_rad : params_.altitude_rad;
  command.azimuth_rad = current_.tablet ? current_.azimuth_rad : params_.azimuth_rad;
  return command;
}

}  // namespace hattr::studio
