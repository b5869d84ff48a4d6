#include "avr_board.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include <simavr/avr_adc.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_cycle_timers.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_irq.h>

#include "hattr/core/error.hpp"

namespace hattr::emulator {
namespace {

// ATmega328P data-space addresses (datasheet, "Register Summary").
constexpr std::uint16_t kPortB = 0x25;
constexpr std::uint16_t kPortD = 0x2B;
constexpr std::uint16_t kTccr2a = 0xB0;
constexpr std::uint16_t kOcr2a = 0xB3;
constexpr std::uint16_t kOcr2b = 0xB4;
constexpr std::uint32_t kFrequency_hz = 16'000'000;
constexpr std::uint32_t kSupply_mV = 5000;

// The quadrature states in order, as (B << 1) | A: A leads B when the count goes up.
constexpr std::uint8_t kGray[4] = {0, 1, 3, 2};

/// simavr's default sleep waits in wall time; simulated time only skips ahead here.
void skipSleep(avr_t*, avr_cycle_count_t) {}

/// simavr's messages go to stderr (stdout carries the pty's name), warnings and errors only.
void logToStderr(avr_t*, const int level, const char* format, va_list arguments) {
  if (level <= LOG_WARNING) std::vfprintf(stderr, format, arguments);
}

/// What elf_read_firmware allocated for the caller (simavr leaves it to us).
void releaseFirmware(elf_firmware_t& firmware) {
  std::free(firmware.flash);
  std::free(firmware.eeprom);
  std::free(firmware.fuse);
  std::free(firmware.lockbits);
#if ELF_SYMBOLS
  for (std::uint32_t i = 0; i < firmware.symbolcount; ++i) std::free(firmware.symbol[i]);
  std::free(firmware.symbol);
#endif
  firmware = elf_firmware_t{};
}

/// The share of the supply a fast-PWM output gives: (OCR + 1) / 256 while the compare output is
/// connected (COM2x1), else the port bit as a plain output.
double pwmShare(const std::uint8_t* data, std::uint16_t ocr, std::uint8_t com_bit, bool port_bit) {
  if ((data[kTccr2a] & (1u << com_bit)) == 0) return port_bit ? 1.0 : 0.0;
  return (data[ocr] + 1.0) / 256.0;
}

}  // namespace

AvrBoard::AvrBoard(BoardOptions options) : options_(std::move(options)), plant_(options_.plant) {
  avr_global_logger_set(logToStderr);
  elf_firmware_t firmware{};
  HATTR_THROW_UNLESS(elf_read_firmware(options_.firmware.c_str(), &firmware) == 0,
                     "{}: cannot read the firmware: expected an AVR ELF file (firmware/openpen)", options_.firmware.string());
  avr_ = avr_make_mcu_by_name("atmega328p");
  HATTR_THROW_UNLESS(avr_ != nullptr, "simavr has no atmega328p core");
  avr_init(avr_);
  avr_->frequency = kFrequency_hz;
  avr_->vcc = avr_->avcc = avr_->aref = kSupply_mV;
  avr_->sleep = skipSleep;
  avr_load_firmware(avr_, &firmware);
  releaseFirmware(firmware);  // the chip has its own copy of the code
  avr_->frequency = kFrequency_hz;  // the ELF names no clock: the Uno's crystal

  // The UART: no console echo, no wall-clock sleeps while the firmware polls.
  std::uint32_t flags = 0;
  avr_ioctl(avr_, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
  flags &= ~static_cast<std::uint32_t>(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
  avr_ioctl(avr_, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), uartOutput, this);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON), uartXon, this);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF), uartXoff, this);
  uart_input_ = avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);

  // The encoders on PD4..PD7 at their home state, the button (PC1) released, the sensor at rest.
  for (int pin = 0; pin < 4; ++pin) encoder_pins_[pin] = avr_io_getirq(avr_, AVR_IOCTL_IOPORT_GETIRQ('D'), 4 + pin);
  setEncoderPins(0);
  setEncoderPins(1);
  avr_raise_irq(avr_io_getirq(avr_, AVR_IOCTL_IOPORT_GETIRQ('C'), 1), 1);
  adc0_ = avr_io_getirq(avr_, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0);
  stepPlant();
  avr_cycle_timer_register(avr_, cycles(options_.plant_step_s), plantTimer, this);
}

AvrBoard::~AvrBoard() {
  if (avr_ != nullptr) avr_terminate(avr_);
}

std::uint64_t AvrBoard::cycles(double seconds) const noexcept {
  return static_cast<std::uint64_t>(std::llround(seconds * kFrequency_hz));
}

double AvrBoard::now_s() const noexcept { return static_cast<double>(avr_->cycle) / kFrequency_hz; }

void AvrBoard::run() {
  const int state = avr_run(avr_);
  HATTR_THROW_UNLESS(state != cpu_Crashed && state != cpu_Done, "the simulated ATmega328P stopped (state {}) at {:.6f} s",
                     state, now_s());
}

void AvrBoard::startHand() noexcept {
  hand_started_ = true;
  hand_start_s_ = now_s();
  if (options_.hand != nullptr) options_.hand->rewind();
}

void AvrBoard::inject(const std::uint8_t* bytes, std::size_t n, double delay_s) {
  pending_input_.insert(pending_input_.end(), bytes, bytes + n);
  if (inject_scheduled_ || pending_input_.empty()) return;
  inject_scheduled_ = true;
  avr_cycle_timer_register(avr_, std::max<std::uint64_t>(cycles(delay_s), 1), injectTimer, this);
}

// ---- the plant, stepped on its own cycle timer ----

std::uint64_t AvrBoard::plantTimer(avr_t*, std::uint64_t when, void* self) {
  auto* board = static_cast<AvrBoard*>(self);
  board->stepPlant();
  return when + board->cycles(board->options_.plant_step_s);
}

void AvrBoard::stepPlant() {
  // The H-bridge: STBY (PD2) on, then per motor IN1/IN2 and the PWM share.
  const std::uint8_t* data = avr_->data;
  const bool standby_off = (data[kPortD] & (1u << 2)) != 0;
  const bool in[4] = {(data[kPortB] & 0x01u) != 0, (data[kPortB] & 0x02u) != 0, (data[kPortB] & 0x04u) != 0,
                      (data[kPortB] & 0x10u) != 0};
  const double share[2] = {pwmShare(data, kOcr2a, 7, (data[kPortB] & 0x08u) != 0),
                           pwmShare(data, kOcr2b, 5, (data[kPortD] & 0x08u) != 0)};
  device::Vec2 duty = device::Vec2::Zero();
  std::array<bool, 2> driven{};
  for (int m = 0; m < 2; ++m) {
    const bool a = in[2 * m];
    const bool b = in[2 * m + 1];
    driven[static_cast<std::size_t>(m)] = standby_off && (a || b);  // both low: stop (coast)
    duty[m] = a == b ? 0.0 : (a ? share[m] : -share[m]);            // both high: short brake
  }

  // The hand writes from the first STATE of a stream on.
  HandCommand command;
  const HandCommand* hand = nullptr;
  if (hand_started_ && options_.hand != nullptr) {
    command = options_.hand->command(now_s() - hand_start_s_);
    hand = &command;
  }
  plant_.step(options_.plant_step_s, duty, driven, hand);

  // The sensor's voltage on ADC0 (10-bit against AVCC).
  const device::PlanarPenSpec& spec = options_.plant.spec;
  const double count = spec.sensor_zero_count + plant_.normalForce_N() / spec.sensor_N_per_count;
  const double mV = std::clamp(count * kSupply_mV / 1024.0, 0.0, static_cast<double>(kSupply_mV));
  avr_raise_irq(adc0_, static_cast<std::uint32_t>(std::lround(mV)));

  // Encoder edges toward the joints' counts, spread evenly over the next step as a turning
  // encoder gives them (never closer than the spacing).
  const double per_count = 2.0 * std::numbers::pi / spec.counts_per_joint_rev;
  double owed = 0.0;
  for (int e = 0; e < 2; ++e) {
    owed = std::max(owed, std::abs(std::floor((plant_.q()[e] - spec.home_q[e]) / per_count + 0.5) - emitted_count_[e]));
  }
  edge_interval_s_ = std::max(options_.encoder_edge_spacing_s, options_.plant_step_s / std::max(owed, 1.0));
  if (owed > 0.0 && !edges_scheduled_) {
    edges_scheduled_ = true;
    avr_cycle_timer_register(avr_, cycles(edge_interval_s_), edgeTimer, this);
  }
  if (options_.trace != nullptr && ++plant_steps_ % 10 == 0) writeTrace();
}

std::uint64_t AvrBoard::edgeTimer(avr_t*, std::uint64_t when, void* self) {
  auto* board = static_cast<AvrBoard*>(self);
  const device::PlanarPenSpec& spec = board->options_.plant.spec;
  const double per_count = 2.0 * std::numbers::pi / spec.counts_per_joint_rev;
  bool moving = false;
  for (int e = 0; e < 2; ++e) {
    const auto target = static_cast<std::int32_t>(std::floor((board->plant_.q()[e] - spec.home_q[e]) / per_count + 0.5));
    std::int32_t& emitted = board->emitted_count_[e];
    if (emitted == target) continue;
    emitted += target > emitted ? 1 : -1;
    board->setEncoderPins(e);
    moving = moving || emitted != target;
  }
  if (!moving) {
    board->edges_scheduled_ = false;
    return 0;
  }
  return when + board->cycles(board->edge_interval_s_);
}

void AvrBoard::setEncoderPins(int encoder) {
  const std::uint8_t state = kGray[static_cast<std::uint32_t>(emitted_count_[encoder]) & 3u];
  avr_raise_irq(encoder_pins_[2 * encoder], state & 1u);
  avr_raise_irq(encoder_pins_[2 * encoder + 1], (state >> 1) & 1u);
  // simavr sets an input pin to its pull-up's level whenever the firmware writes its port (simavr
  // issue 432): the encoders drive PD4..PD7, so those pins keep the encoders' levels instead.
  std::uint32_t levels = 0;
  for (int e = 0; e < 2; ++e) levels |= static_cast<std::uint32_t>(kGray[static_cast<std::uint32_t>(emitted_count_[e]) & 3u]) << (4 + 2 * e);
  avr_ioport_external_t external{};
  external.name = 'D';
  external.mask = 0xF0;
  external.value = levels & 0xF0u;
  avr_ioctl(avr_, AVR_IOCTL_IOPORT_SET_EXTERNAL('D'), &external);
}

void AvrBoard::writeTrace() {
  const device::Vec2& q = plant_.q();
  const Vec3& p = plant_.penPosition();
  std::fprintf(options_.trace, "%.4f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d\n", now_s(), q[0], q[1], p.x(), p.y(),
               plant_.normalForce_N(), plant_.motorTorque()[0], plant_.motorTorque()[1], emitted_count_[0],
               emitted_count_[1]);
}

// ---- the UART ----

void AvrBoard::uartOutput(avr_irq_t*, std::uint32_t value, void* self) {
  auto* board = static_cast<AvrBoard*>(self);
  if (board->on_output_) board->on_output_(static_cast<std::uint8_t>(value));
}

void AvrBoard::uartXon(avr_irq_t*, std::uint32_t, void* self) { static_cast<AvrBoard*>(self)->uart_ready_ = true; }
void AvrBoard::uartXoff(avr_irq_t*, std::uint32_t, void* self) { static_cast<AvrBoard*>(self)->uart_ready_ = false; }

std::uint64_t AvrBoard::injectTimer(avr_t*, std::uint64_t when, void* self) {
  auto* board = static_cast<AvrBoard*>(self);
  if (board->uart_ready_ && !board->pending_input_.empty()) {
    avr_raise_irq(board->uart_input_, board->pending_input_.front());
    board->pending_input_.pop_front();
  }
  if (board->pending_input_.empty()) {
    board->inject_scheduled_ = false;
    return 0;
  }
  return when + board->cycles(10.0 / board->options_.baud);
}

}  // namespace hattr::emulator
