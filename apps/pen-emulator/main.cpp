// hattr-pen-emulator: the open pen's unmodified firmware under simavr, with the simulated
// pantograph, hand and table around it, behind a pseudo-terminal hattr opens as serial://PATH
// (docs/hardware.md, "The emulator").
//
// Two clocks. Lockstep (the default, for tests): the chip stops after each frame it sends until
// the host's answer has come, then the answer reaches the UART a fixed simulated latency later;
// the same host gives the same run, bit for bit. Real time: simulated time follows the wall clock
// and the host's bytes reach the UART when they arrive (a smoke check of timing).

#include <signal.h>
#include <unistd.h>

#include <atomic>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "avr_board.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/install_layout.hpp"
#include "hattr/core/units.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/openpen/protocol.h"
#include "hattr/session/trial.hpp"
#include "pty_port.hpp"

namespace {

/// SIGTERM or SIGINT: stop after the current instruction (the trace is complete up to there).
std::atomic<bool> g_stop{false};
void requestStop(int) { g_stop.store(true); }

using hattr::emulator::AvrBoard;
using hattr::emulator::PtyPort;

struct Options {
  std::filesystem::path firmware;
  std::filesystem::path hand;
  double settle_s = 0.3;
  std::string clock = "lockstep";
  std::filesystem::path trace;
  std::filesystem::path link;
  int reply_timeout_ms = 0;
  double latency_us = 200.0;
  double linger_ms = 100.0;
  int hangups = 0;
  double duration_s = 0.0;
};

/// What the emulator waits for before the chip runs on (lockstep).
enum class Await { kNothing, kHost, kReply };

class Emulator {
 public:
  Emulator(const Options& options, AvrBoard& board, PtyPort& pty) : options_(options), board_(board), pty_(pty) {
    hpen_parser_reset(&from_device_);
    hpen_parser_reset(&from_host_);
    board_.onOutput([this](std::uint8_t byte) { deviceByte(byte); });
  }

  /// Runs until the host has hung up --hangups times, the duration has passed or a signal came.
  void run() {
    const bool lockstep = options_.clock == "lockstep";
    const auto wall_start = std::chrono::steady_clock::now();
    double next_poll_s = 0.0;
    while (!g_stop.load(std::memory_order_relaxed)) {
      if (lockstep && await_ != Await::kNothing && !lingering()) waitForHost();
      if (!lockstep && board_.now_s() >= next_poll_s) {
        next_poll_s += 1e-4;
        pace(wall_start);
        take(pty_.read(0), 0.0);
      }
      // After the host's STOP has reached the chip, simulated time waits for the host again.
      if (lockstep && freeze_at_s_ && board_.now_s() >= *freeze_at_s_) {
        freeze_at_s_.reset();
        await_ = Await::kHost;
      }
      if (lingering() && board_.now_s() >= linger_until_s_) {
        if (options_.hangups > 0 && hangups_ >= options_.hangups) return;
        linger_until_s_.reset();
        await_ = Await::kHost;
      }
      if (options_.duration_s > 0.0 && board_.now_s() >= options_.duration_s) return;
      board_.run();
    }
  }

 private:
  bool lingering() const noexcept { return linger_until_s_.has_value(); }

  void waitForHost() {
    // The first contact and the start of a stream wait as long as the host takes; so does an
    // answer to a STATE, unless a reply timeout is set (then the chip runs on without it, as a
    // real one would: what a test of the firmware's watchdog needs).
    const int timeout = await_ == Await::kReply && options_.reply_timeout_ms > 0 ? options_.reply_timeout_ms : -1;
    PtyPort::Read read;
    do {
      if (g_stop.load(std::memory_order_relaxed)) return;
      read = pty_.read(timeout);
      take(read, options_.latency_us * 1e-6);
    } while (!host_frame_done_ && !read.hung_up && !read.bytes.empty());
    await_ = Await::kNothing;
  }

  void take(const PtyPort::Read& read, double latency_s) {
    if (read.hung_up) {
      ++hangups_;
      linger_until_s_ = board_.now_s() + options_.linger_ms * 1e-3;
      std::fprintf(stderr, "hattr-pen-emulator: the host hung up at %.6f s\n", board_.now_s());
      return;
    }
    host_frame_done_ = false;
    for (std::uint8_t byte : read.bytes) {
      const hpen_event event = hpen_parser_feed(&from_host_, byte);
      if (event == HPEN_NONE) continue;
      host_frame_done_ = true;
      if (event == HPEN_FRAME && hpen_parser_type(&from_host_) == HPEN_START) hand_pending_ = true;
      if (event == HPEN_FRAME && hpen_parser_type(&from_host_) == HPEN_STOP) freeze_at_s_ = board_.now_s() + kStopSettle_s;
    }
    if (!read.bytes.empty()) board_.inject(read.bytes.data(), read.bytes.size(), latency_s);
  }

  void deviceByte(std::uint8_t byte) {
    pty_.write(byte);
    // Any whole frame counts, of this emulator's protocol version or not (a firmware of another
    // version still answers a HELLO).
    const hpen_event event = hpen_parser_feed(&from_device_, byte);
    if (event != HPEN_NONE) pty_.flush();  // a whole frame (or what the host will call a bad one)
    if (event != HPEN_FRAME && event != HPEN_WRONG_VERSION) return;
    const std::uint8_t type = hpen_parser_type(&from_device_);
    if (type == HPEN_STATE && hand_pending_) {
      hand_pending_ = false;
      board_.startHand();
      std::fprintf(stderr, "hattr-pen-emulator: a stream began at %.6f s\n", board_.now_s());
    }
    await_ = type == HPEN_STATE ? Await::kReply : Await::kHost;
  }

  /// Real time: simulated time waits for the wall clock.
  void pace(std::chrono::steady_clock::time_point start) const {
    const auto due = start + std::chrono::nanoseconds(hattr::units::secondsToNanoseconds(board_.now_s()));
    if (due > std::chrono::steady_clock::now()) std::this_thread::sleep_until(due);
  }

  const Options& options_;
  AvrBoard& board_;
  PtyPort& pty_;
  hpen_parser from_device_{};
  hpen_parser from_host_{};
  Await await_ = Await::kHost;
  bool host_frame_done_ = false;
  bool hand_pending_ = false;
  std::optional<double> linger_until_s_;
  std::optional<double> freeze_at_s_;
  static constexpr double kStopSettle_s = 0.002;  // the STOP's bytes reach the UART well within this
  int hangups_ = 0;
};

int run(const Options& options) {
  // The hand as a hattr trial holds it: lifted over the script's start for the settle phase, then
  // writing the script (session::SettlingHand).
  std::unique_ptr<hattr::device::ProfileHandScript> script;
  std::unique_ptr<hattr::session::SettlingHand> hand;
  if (!options.hand.empty()) {
    script = std::make_unique<hattr::device::ProfileHandScript>(hattr::io::readProfileCsv(options.hand));
    hand = std::make_unique<hattr::session::SettlingHand>(*script, options.settle_s);
  }
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> trace(nullptr, &std::fclose);
  if (!options.trace.empty()) {
    trace.reset(std::fopen(options.trace.c_str(), "w"));
    HATTR_THROW_UNLESS(trace != nullptr, "--trace {}: cannot write it", options.trace.string());
    std::fputs("t_s,q0_rad,q1_rad,x_m,y_m,normal_N,torque0_Nm,torque1_Nm,count0,count1\n", trace.get());
  }
  hattr::emulator::BoardOptions board_options{.firmware = options.firmware, .plant = {}, .hand = hand.get()};
  board_options.trace = trace.get();
  AvrBoard board(board_options);
  PtyPort pty;
  if (!options.link.empty()) {
    std::filesystem::remove(options.link);
    std::filesystem::create_symlink(pty.name(), options.link);
  }
  struct sigaction stop{};
  stop.sa_handler = requestStop;
  sigaction(SIGTERM, &stop, nullptr);
  sigaction(SIGINT, &stop, nullptr);
  std::printf("pty: %s\n", pty.name().c_str());
  std::fflush(stdout);
  Emulator(options, board, pty).run();
  if (!options.link.empty()) std::filesystem::remove(options.link);
  std::fprintf(stderr, "hattr-pen-emulator: ran %.6f s of simulated time; %llu bytes to the host dropped\n", board.now_s(),
               static_cast<unsigned long long>(pty.droppedOutput()));
  return 0;
}

/// The reference firmware in the share folder of the prefix this program is in.
std::filesystem::path installedFirmware() {
  const std::filesystem::path in_share = std::filesystem::path("firmware") / "openpen-atmega328p.elf";
  if (const auto share = hattr::findShareDir(); share && std::filesystem::is_regular_file(*share / in_share)) {
    return *share / in_share;
  }
  throw hattr::InputError(fmt::format(
      "--firmware: not given, and no installed firmware: expected PREFIX/{}/{}, looked in {}; give the ELF with "
      "--firmware", hattr::relativeShareDir().string(), in_share.string(), hattr::searchedShareDirs()));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The open pen's firmware under simavr, with the simulated pantograph, hand and table, behind a "
               "pseudo-terminal: hattr opens it as serial://PTY (docs/hardware.md)"};
  Options options;
  app.add_option("--firmware", options.firmware,
                 "The firmware ELF (built for an ATmega328P at 16 MHz); default: the one hattr installs, "
                 "PREFIX/share/hattr/firmware/openpen-atmega328p.elf")
      ->check(CLI::ExistingFile);
  app.add_option("--hand", options.hand, "A haptic profile (CSV) the simulated hand writes from the first STATE of a "
                                         "stream on (default: nobody holds the pen)")
      ->check(CLI::ExistingFile);
  app.add_option("--settle", options.settle_s,
                 "The hand holds the pen lifted over the script's start this long first, as a hattr trial's settle "
                 "phase (`hattr record`, `hattr train`: 0.3 s) [s]")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  app.add_option("--clock", options.clock, "lockstep (deterministic) or realtime")
      ->check(CLI::IsMember({"lockstep", "realtime"}))
      ->capture_default_str();
  app.add_option("--trace", options.trace, "Write the plant's state each simulated millisecond to this CSV");
  app.add_option("--link", options.link, "Also make this path a symbolic link to the pseudo-terminal");
  app.add_option("--reply-timeout-ms", options.reply_timeout_ms,
                 "Lockstep: how long the chip waits (wall clock) for the host's answer to a STATE before it runs on "
                 "without one; 0: for as long as the host takes (the same run every time)")
      ->check(CLI::Range(0, 60000))
      ->capture_default_str();
  app.add_option("--latency-us", options.latency_us, "Lockstep: simulated time from the host's answer to the UART")
      ->check(CLI::Range(0.0, 10000.0))
      ->capture_default_str();
  app.add_option("--linger-ms", options.linger_ms, "Simulated time the chip runs on after the host hangs up")
      ->check(CLI::Range(0.0, 60000.0))
      ->capture_default_str();
  app.add_option("--hangups", options.hangups,
                 "Exit once the host has hung up this many times (and the chip has run on for the linger); 0: never")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  app.add_option("--duration", options.duration_s, "Stop after this much simulated time [s] (0: no limit)")
      ->check(CLI::Range(0.0, 1e6));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (options.firmware.empty()) options.firmware = installedFirmware();
    return run(options);
  } catch (const hattr::InputError& e) {
    std::fprintf(stderr, "hattr-pen-emulator: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hattr-pen-emulator: %s\n", e.what());
    return 1;
  }
}
