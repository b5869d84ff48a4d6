#pragma once
/// A serial port in raw mode (private to the device module): open, set the baud, write without
/// blocking, wait for bytes. POSIX termios; a pseudo-terminal works the same.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace hattr::device {

class SerialPort {
 public:
  /// Opens `path` raw (8N1, no flow control) at `baud`. Throws InputError naming the port and
  /// the system's reason, or the baud rates accepted.
  SerialPort(const std::filesystem::path& path, unsigned baud);
  ~SerialPort();
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  /// Writes all of `bytes`, waiting up to 2 ms for room; false when the port has gone or stayed full.
  bool write(const std::uint8_t* bytes, std::size_t n) noexcept;

  enum class Wait { kBytes, kTimeout, kClosed };
  /// Waits up to `timeout_ms` for bytes; reads what is there into `buffer` (`n` set). kClosed: the
  /// other end has gone (an unplugged cable, a closed pseudo-terminal).
  Wait read(int timeout_ms, std::uint8_t* buffer, std::size_t capacity, std::size_t& n) noexcept;

  /// Whether `baud` is one the port can be set to.
  static bool baudSupported(unsigned baud) noexcept;
  static std::string supportedBauds();

 private:
  int fd_ = -1;
};

}  // namespace hattr::device
