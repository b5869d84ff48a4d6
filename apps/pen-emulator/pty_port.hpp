#pragma once
/// The emulated board's USB serial port: a pseudo-terminal whose other end (its /dev/pts/N name)
/// hattr opens as serial://PATH. hattr-pen-emulator's own bridge: the bytes the firmware's UART
/// sends are written at once; what the host writes is read when the emulator asks, so simulated
/// time decides when it reaches the chip (not the wall clock).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace hattr::emulator {

class PtyPort {
 public:
  /// Opens a pseudo-terminal in raw mode. Throws hattr::Error if the system has none to give.
  PtyPort();
  ~PtyPort();
  PtyPort(const PtyPort&) = delete;
  PtyPort& operator=(const PtyPort&) = delete;

  /// The path the host opens (/dev/pts/N).
  [[nodiscard]] const std::string& name() const noexcept { return name_; }

  /// Queues a byte for the host (sent by flush(), as a USB serial bridge sends its packets).
  void write(std::uint8_t byte) { pending_.push_back(byte); }
  /// Sends what is queued; a full buffer (a host that stopped reading) or no host drops it.
  void flush() noexcept;

  struct Read {
    std::vector<std::uint8_t> bytes;
    bool hung_up = false;  ///< the host had the port open and closed it (an unplugged cable)
  };
  /// Waits up to `timeout_ms` (negative: for ever) for bytes from the host and returns what came.
  /// Before the host first opens the port, waiting goes on until it does or the time is up.
  Read read(int timeout_ms);

  /// Bytes dropped because the host was not reading.
  [[nodiscard]] std::uint64_t droppedOutput() const noexcept { return dropped_output_; }

 private:
  int master_ = -1;
  std::string name_;
  bool connected_ = false;
  std::uint64_t dropped_output_ = 0;
  std::vector<std::uint8_t> pending_;
};

}  // namespace hattr::emulator
