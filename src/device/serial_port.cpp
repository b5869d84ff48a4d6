#include "serial_port_internal.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::device {
namespace {

constexpr std::pair<unsigned, speed_t> kBauds[] = {
    {9600, B9600},     {19200, B19200},   {38400, B38400},     {57600, B57600},     {115200, B115200},
    {230400, B230400}, {460800, B460800}, {500000, B500000},   {921600, B921600},   {1000000, B1000000},
    {2000000, B2000000}};

}  // namespace

bool SerialPort::baudSupported(unsigned baud) noexcept {
  for (const auto& [value, code] : kBauds) {
    if (value == baud) return true;
  }
  return false;
}

std::string SerialPort::supportedBauds() {
  std::string text;
  for (const auto& [value, code] : kBauds) text += (text.empty() ? "" : ", ") + std::to_string(value);
  return text;
}

SerialPort::SerialPort(const std::filesystem::path& path, unsigned baud) {
  speed_t speed = B0;
  for (const auto& [value, code] : kBauds) {
    if (value == baud) speed = code;
  }
  HATTR_THROW_UNLESS(speed != B0, "serial port {}: baud {} is not one of {}", path.string(), baud, supportedBauds());
  fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  HATTR_THROW_UNLESS(fd_ >= 0, "serial port {}: cannot open it: {}", path.string(), std::strerror(errno));
  // Raw 8N1 without flow control; HUPCL off: DTR stays up when the port closes, so an Arduino
  // resets only when the port is first opened (later opens find it running, still homed).
  termios settings{};
  const bool configured = tcgetattr(fd_, &settings) == 0 && (cfmakeraw(&settings), true) &&
                          cfsetispeed(&settings, speed) == 0 && cfsetospeed(&settings, speed) == 0 &&
                          ((settings.c_cflag |= CLOCAL | CREAD),
                           (settings.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | HUPCL)), true) &&
                          tcsetattr(fd_, TCSANOW, &settings) == 0;
  if (!configured) {
    const std::string reason = std::strerror(errno);
    ::close(fd_);
    throw InputError(fmt::format("serial port {}: not a serial port (cannot set it raw at {} baud): {}", path.string(),
                                 baud, reason));
  }
  tcflush(fd_, TCIOFLUSH);
}

SerialPort::~SerialPort() {
  if (fd_ >= 0) ::close(fd_);
}

bool SerialPort::write(const std::uint8_t* bytes, std::size_t n) noexcept {
  // A full output buffer may take part of a frame: finish it (up to 2 ms), never leave half a
  // frame to corrupt the next.
  std::size_t sent = 0;
  for (int wait = 0; sent < n && wait < 3; ++wait) {
    const ssize_t done = ::write(fd_, bytes + sent, n - sent);
    if (done > 0) sent += static_cast<std::size_t>(done);
    if (done < 0 && errno != EAGAIN && errno != EINTR) return false;
    if (sent < n) {
      pollfd fd{.fd = fd_, .events = POLLOUT, .revents = 0};
      (void)::poll(&fd, 1, 1);
    }
  }
  return sent == n;
}

SerialPort::Wait SerialPort::read(int timeout_ms, std::uint8_t* buffer, std::size_t capacity, std::size_t& n) noexcept {
  n = 0;
  pollfd fd{.fd = fd_, .events = POLLIN, .revents = 0};
  const int ready = ::poll(&fd, 1, timeout_ms);
  if (ready == 0 || (ready < 0 && errno == EINTR)) return Wait::kTimeout;
  if (ready < 0) return Wait::kClosed;
  if ((fd.revents & POLLIN) != 0) {
    const ssize_t got = ::read(fd_, buffer, capacity);
    if (got > 0) {
      n = static_cast<std::size_t>(got);
      return Wait::kBytes;
    }
    if (got < 0 && (errno == EAGAIN || errno == EINTR)) return Wait::kTimeout;
    return Wait::kClosed;
  }
  return (fd.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0 ? Wait::kClosed : Wait::kTimeout;
}

}  // namespace hattr::device
