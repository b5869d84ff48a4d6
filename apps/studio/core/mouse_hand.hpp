#pragma once
/// The person's hand in the studio: the mouse holds the simulated pen. The GUI thread
/// publishes what the mouse does (cursor on the paper, left button = pen down, the press
/// force set with the wheel or a slider) through a lock-free triple buffer; the servo thread
/// turns it into hand commands. The cursor moves in steps of a display frame, so the hand
/// follows it through a critically damped second-order filter (no force steps, a smooth
/// target velocity), and the press force rises and falls with a first-order lag.
///
/// Should move into the library (device/) as a generic "live hand" whose input comes from
/// any GUI or tablet thread.

#include "hattr/core/triple_buffer.hpp"
#include "hattr/device/hand.hpp"

namespace hattr::studio {

/// What the person does with the mouse, as the GUI thread last saw it. Frame W, SI.
struct MouseInput {
  double x_m = 0.0;       ///< cursor on the paper [m]
  double y_m = 0.0;       ///< cursor on the paper [m]
  bool pen_down = false;  ///< the left button is held: the hand means to write
  double press_N = 1.2;   ///< intended axial force while writing [N] (wheel / slider)
  /// A pen tablet is the hand (QTabletEvent): the pen angles and press force below replace
  /// the mouse hand's fixed tilt and press_N (which keeps the wheel's setting).
  bool tablet = false;
  double tablet_press_N = 0.0;                 ///< from the tablet's pressure [N]
  double altitude_rad = 1.0471975511965976;    ///< from the tablet's tilt [rad]
  double azimuth_rad = 2.356194490192345;      ///< from the tablet's tilt [rad]
};

/// The press force a person sets with the wheel or the slider [N].
struct PressScale {
  static constexpr double kMin_N = 0.0;
  static constexpr double kMax_N = 3.0;
  static constexpr double kStep_N = 0.1;     ///< one wheel notch
  static constexpr double kDefault_N = 1.2;  ///< about 1 N on the paper at 60°
  /// The force after turning the wheel by `angle_delta_eighths` (Qt's angleDelta: 120 per
  /// notch), clamped to [kMin_N, kMax_N] and rounded to the step.
  static double afterWheel(double press_N, int angle_delta_eighths) noexcept;
  /// A slider position in steps of kStep_N → newtons, clamped.
  static double fromSliderSteps(int steps) noexcept;
  /// Newtons → the nearest slider step, clamped.
  static int toSliderSteps(double press_N) noexcept;
};

class MouseHand final : public device::HandScript {
 public:
  struct Params {
    double follow_hz = 12.0;  ///< natural frequency of the cursor-following filter
    double press_time_constant_s = 0.03;
    double lift_height_m = 0.003;              ///< pen up: the hand holds the tip this high
    double altitude_rad = 1.0471975511965976;  ///< pen held at 60° above the paper
    double azimuth_rad = 2.356194490192345;    ///< barrel toward the writer's lower right
  };

  MouseHand() : MouseHand(Params{}) {}
  explicit MouseHand(const Params& params);

  /// Publishes the newest input. GUI thread only (the single writer); never blocks.
  void setInput(const MouseInput& input) noexcept;
  /// The input last published (the GUI thread's copy).
  [[nodiscard]] const MouseInput& input() const noexcept { return gui_input_; }

  /// The hand command at loop time t_s. Servo thread only: noexcept, no allocation, no locks.
  device::HandCommand command(double t_s) noexcept override;
  /// The next command starts at the current input, at rest. Not while the loop runs.
  void rewind() noexcept override;

  [[nodiscard]] const Params& params() const noexcept { return params_; }

 private:
  Params params_;
  TripleBuffer<MouseInput> buffer_;
  MouseInput gui_input_;
  // Servo-thread state.
  MouseInput current_;
  bool started_ = false;
  double last_t_s_ = 0.0;
  double x_m_ = 0.0, y_m_ = 0.0, vx_ = 0.0, vy_ = 0.0;
  double press_N_ = 0.0;
};

}  // namespace hattr::studio
