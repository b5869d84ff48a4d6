#pragma once
// The open pen's tests (tests/integration/openpen_*_test.cpp): the emulator started as a real
// process, and a host that speaks the protocol byte by byte over a serial port or pty.

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/openpen/protocol.h"
#include "support/background_process.hpp"
#include "support/test_support.hpp"

namespace hattr::test {

/// The emulator and the firmware the build made, or "" when the AVR toolchain or simavr was
/// missing (the tests then skip, saying so).
inline std::string penEmulator() { return builtFile("HATTR_PEN_EMULATOR"); }
inline std::string penFirmware() { return builtFile("HATTR_OPENPEN_FIRMWARE"); }
inline std::string penFirmwareV2() { return builtFile("HATTR_OPENPEN_FIRMWARE_V2"); }
#define HATTR_SKIP_WITHOUT_OPEN_PEN()                                                                           \
  if (::hattr::test::penEmulator().empty() || ::hattr::test::penFirmware().empty())                             \
  GTEST_SKIP() << "the open pen's firmware or emulator was not built: avr-gcc, avr-libc, simavr and "           \
                  "libsimavr-dev are missing (scripts/install-deps installs them)"

/// hattr-pen-emulator running the firmware; its pty's path from its first line.
class PenEmulator {
 public:
  PenEmulator(const TempDir& dir, std::vector<std::string> args, const std::string& firmware = penFirmware()) {
    std::vector<std::string> all = {penEmulator(), "--firmware", firmware};
    all.insert(all.end(), args.begin(), args.end());
    process_ = std::make_unique<BackgroundProcess>(all, dir / "emulator.err");
    const std::string& line = process_->firstLine();
    if (line.starts_with("pty: ")) pty_ = line.substr(5);
  }
  [[nodiscard]] const std::string& pty() const { return pty_; }
  BackgroundProcess& process() { return *process_; }

 private:
  std::unique_ptr<BackgroundProcess> process_;
  std::string pty_;
};

/// One frame as it came, or what the parser said about it.
struct Frame {
  hpen_event event = HPEN_NONE;
  std::uint8_t version = 0;
  std::uint8_t type = 0;
  std::vector<std::uint8_t> payload;
};

/// The host side of the protocol on a raw port (a test plays hattr, or the pen).
class ProtocolPort {
 public:
  /// Opens a tty path raw, or takes an open descriptor (a pty's master).
  explicit ProtocolPort(const std::string& path) : fd_(::open(path.c_str(), O_RDWR | O_NOCTTY)) { makeRaw(); }
  explicit ProtocolPort(int fd) : fd_(fd) { makeRaw(); }
  ~ProtocolPort() { close(); }
  ProtocolPort(const ProtocolPort&) = delete;
  ProtocolPort& operator=(const ProtocolPort&) = delete;

  [[nodiscard]] bool open() const { return fd_ >= 0; }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

  /// Frames and sends a payload; returns the bytes sent.
  std::vector<std::uint8_t> send(std::uint8_t type, const std::uint8_t* payload, std::uint8_t n,
                                 std::uint8_t version = HPEN_PROTOCOL_VERSION) {
    std::uint8_t frame[HPEN_MAX_FRAME_BYTES];
    const std::uint8_t length = hpen_frame(frame, version, type, payload, n);
    sendBytes({frame, frame + length});
    return {frame, frame + length};
  }
  void sendBytes(const std::vector<std::uint8_t>& bytes) {
    EXPECT_EQ(::write(fd_, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }
  void hello(std::uint32_t nonce, std::uint8_t version = HPEN_PROTOCOL_VERSION) {
    const hpen_hello h{.nonce = nonce};
    std::uint8_t p[HPEN_HELLO_BYTES];
    hpen_encode_hello(p, &h);
    send(HPEN_HELLO, p, HPEN_HELLO_BYTES, version);
  }
  void start(std::uint8_t flags) {
    const hpen_start s{.flags = flags};
    std::uint8_t p[HPEN_START_BYTES];
    hpen_encode_start(p, &s);
    send(HPEN_START, p, HPEN_START_BYTES);
  }
  std::vector<std::uint8_t> command(std::uint16_t seq, std::int16_t e0, std::int16_t e1, bool send_now = true) {
    const hpen_command c{.seq = seq, .effort0 = e0, .effort1 = e1, .flags = HPEN_COMMAND_ENABLE};
    std::uint8_t p[HPEN_COMMAND_BYTES];
    hpen_encode_command(p, &c);
    std::uint8_t frame[HPEN_MAX_FRAME_BYTES];
    const std::uint8_t length = hpen_frame(frame, HPEN_PROTOCOL_VERSION, HPEN_COMMAND, p, HPEN_COMMAND_BYTES);
    std::vector<std::uint8_t> bytes(frame, frame + length);
    if (send_now) sendBytes(bytes);
    return bytes;
  }

  /// The next frame (or bad frame) within `timeout`; nullopt when none came or the port closed.
  std::optional<Frame> next(std::chrono::milliseconds timeout = std::chrono::milliseconds(5000)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      while (head_ < buffer_.size()) {
        const hpen_event e = hpen_parser_feed(&parser_, buffer_[head_++]);
        if (e == HPEN_NONE) continue;
        const std::uint8_t n = hpen_payload_bytes(hpen_parser_type(&parser_));
        const std::uint8_t* p = hpen_parser_payload(&parser_);
        return Frame{e, hpen_parser_version(&parser_), hpen_parser_type(&parser_), std::vector<std::uint8_t>(p, p + n)};
      }
      buffer_.clear();
      head_ = 0;
      pollfd fd{fd_, POLLIN, 0};
      if (::poll(&fd, 1, 20) <= 0) continue;
      std::uint8_t chunk[512];
      const ssize_t got = ::read(fd_, chunk, sizeof chunk);
      if (got <= 0) return std::nullopt;
      buffer_.assign(chunk, chunk + got);
    }
    return std::nullopt;
  }
  /// The next STATE (skipping anything else).
  std::optional<hpen_state> nextState(std::chrono::milliseconds timeout = std::chrono::milliseconds(5000)) {
    for (auto f = next(timeout); f; f = next(timeout)) {
      if (f->event != HPEN_FRAME || f->type != HPEN_STATE) continue;
      hpen_state s{};
      hpen_decode_state(f->payload.data(), &s);
      return s;
    }
    return std::nullopt;
  }

 private:
  void makeRaw() {
    hpen_parser_reset(&parser_);
    termios t{};
    if (fd_ >= 0 && ::tcgetattr(fd_, &t) == 0) {
      ::cfmakeraw(&t);
      ::tcsetattr(fd_, TCSANOW, &t);
    }
  }

  int fd_ = -1;
  hpen_parser parser_{};
  std::vector<std::uint8_t> buffer_;
  std::size_t head_ = 0;
};

}  // namespace hattr::test
