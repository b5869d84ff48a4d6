#pragma once
/// The open pen's board under simavr: the unmodified firmware ELF on a simulated ATmega328P at
/// 16 MHz, wired (as docs/hardware.md wires the real one) to the simulated plant: the H-bridge's
/// pins and PWM registers drive the motors, the linkage's joint angles become quadrature edges on
/// the encoder pins, the hand's press becomes the sensor's voltage on ADC0. The UART is a byte
/// stream both ways; what the firmware sends goes to `on_output`, what the host sends is fed in at
/// the baud rate from `inject()`. Everything runs in simulated time: the same inputs at the same
/// simulated moments give the same run, bit for bit.

#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>

#include "hattr/device/hand.hpp"
#include "hattr/device/planar_pen.hpp"

struct avr_t;
struct avr_irq_t;

namespace hattr::emulator {

struct BoardOptions {
  std::filesystem::path firmware;                 ///< the ELF (built for an ATmega328P at 16 MHz)
  device::PlanarPlantParams plant;
  device::HandScript* hand = nullptr;             ///< null: nobody holds the pen
  double plant_step_s = 1e-4;                     ///< the plant's integration step
  double encoder_edge_spacing_s = 8e-6;           ///< the closest two edges of one encoder come (a fast move)
  double baud = 1e6;
  std::FILE* trace = nullptr;                     ///< one CSV line a millisecond (null: none)
};

class AvrBoard {
 public:
  /// Loads the firmware and resets the chip. Throws hattr::Error when the ELF cannot be read.
  explicit AvrBoard(BoardOptions options);
  ~AvrBoard();
  AvrBoard(const AvrBoard&) = delete;
  AvrBoard& operator=(const AvrBoard&) = delete;

  /// Where the firmware's UART bytes go.
  void onOutput(std::function<void(std::uint8_t)> sink) { on_output_ = std::move(sink); }
  /// Queues host bytes: they reach the UART one a byte time apart, from `delay_s` on.
  void inject(const std::uint8_t* bytes, std::size_t n, double delay_s);
  /// Runs the chip by one instruction (or one stretch of sleep). Throws hattr::Error if it crashed.
  void run();
  /// The hand's clock starts now (the first STATE of a stream).
  void startHand() noexcept;

  [[nodiscard]] double now_s() const noexcept;
  [[nodiscard]] const device::PlanarPlant& plant() const noexcept { return plant_; }

 private:
  static std::uint64_t plantTimer(avr_t* avr, std::uint64_t when, void* self);
  static std::uint64_t edgeTimer(avr_t* avr, std::uint64_t when, void* self);
  static std::uint64_t injectTimer(avr_t* avr, std::uint64_t when, void* self);
  static void uartOutput(avr_irq_t* irq, std::uint32_t value, void* self);
  static void uartXon(avr_irq_t* irq, std::uint32_t value, void* self);
  static void uartXoff(avr_irq_t* irq, std::uint32_t value, void* self);

  void stepPlant();
  void writeTrace();
  void setEncoderPins(int encoder);
  std::uint64_t cycles(double seconds) const noexcept;

  BoardOptions options_;
  avr_t* avr_ = nullptr;
  device::PlanarPlant plant_;
  std::function<void(std::uint8_t)> on_output_;
  std::deque<std::uint8_t> pending_input_;
  bool uart_ready_ = true;
  bool inject_scheduled_ = false;
  std::int32_t emitted_count_[2] = {0, 0};
  bool edges_scheduled_ = false;
  double edge_interval_s_ = 1e-4;  // the edges a plant step owes, spread over the next step
  bool hand_started_ = false;
  double hand_start_s_ = 0.0;
  std::uint64_t plant_steps_ = 0;
  avr_irq_t* encoder_pins_[4] = {};
  avr_irq_t* adc0_ = nullptr;
  avr_irq_t* uart_input_ = nullptr;
};

}  // namespace hattr::emulator
