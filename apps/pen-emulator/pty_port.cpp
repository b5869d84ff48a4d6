#include "pty_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "hattr/core/error.hpp"

namespace hattr::emulator {

PtyPort::PtyPort() {
  master_ = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
  HATTR_THROW_UNLESS(master_ >= 0 && grantpt(master_) == 0 && unlockpt(master_) == 0,
                     "cannot open a pseudo-terminal: {}", std::strerror(errno));
  name_ = ptsname(master_);
  // Raw bytes both ways: no echo, no line editing, no CR/LF translation.
  termios settings{};
  HATTR_THROW_UNLESS(tcgetattr(master_, &settings) == 0, "{}: cannot read its settings: {}", name_, std::strerror(errno));
  cfmakeraw(&settings);
  HATTR_THROW_UNLESS(tcsetattr(master_, TCSANOW, &settings) == 0, "{}: cannot make it raw: {}", name_,
                     std::strerror(errno));
}

PtyPort::~PtyPort() {
  if (master_ >= 0) ::close(master_);
}

void PtyPort::flush() noexcept {
  std::size_t sent = 0;
  while (connected_ && sent < pending_.size()) {
    const ssize_t n = ::write(master_, pending_.data() + sent, pending_.size() - sent);
    if (n <= 0) break;
    sent += static_cast<std::size_t>(n);
  }
  dropped_output_ += pending_.size() - sent;
  pending_.clear();
}

PtyPort::Read PtyPort::read(int timeout_ms) {
  flush();
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  Read out;
  for (;;) {
    pollfd fd{.fd = master_, .events = POLLIN, .revents = 0};
    const int left_ms =
        timeout_ms < 0 ? 50 : static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
    const int ready = ::poll(&fd, 1, std::max(left_ms, 0));
    if (ready < 0 && errno == EINTR) return out;  // a signal: the caller decides
    bool gone = ready > 0 && (fd.revents & POLLHUP) != 0;
    if (ready > 0 && (fd.revents & POLLIN) != 0) {
      std::uint8_t buffer[512];
      const ssize_t n = ::read(master_, buffer, sizeof buffer);
      if (n > 0) {
        connected_ = true;
        out.bytes.assign(buffer, buffer + n);
        return out;
      }
      gone = gone || (n < 0 && errno == EIO);  // no one has the other end open
    }
    // A master reports a hang-up while no one has the other end open: before the host came, that
    // means "not yet"; after, the host has gone.
    if (gone) {
      if (connected_) {
        connected_ = false;
        out.hung_up = true;
        return out;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (timeout_ms >= 0 && Clock::now() >= deadline) return out;
  }
}

}  // namespace hattr::emulator
