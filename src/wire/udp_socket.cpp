#include "hattr/wire/udp_socket.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::wire {
namespace {

sockaddr_in toSockaddr(const UdpEndpoint& e) noexcept {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(e.address);
  a.sin_port = htons(e.port);
  return a;
}

std::int64_t nsOf(const timespec& ts) noexcept {
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// A non-blocking datagram socket asking the kernel for arrival timestamps.
int openSocket(std::string_view what) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw Error(fmt::format("{}: cannot open a UDP socket: {}", what, std::strerror(errno)));
  const int on = 1;
  (void)::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  const int bytes = UdpSocket::kReceiveBufferBytes;
  (void)::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
  return fd;
}

}  // namespace

std::string UdpEndpoint::text() const {
  return fmt::format("{}.{}.{}.{}:{}", address >> 24, (address >> 16) & 0xff, (address >> 8) & 0xff, address & 0xff,
                     port);
}

UdpEndpoint parseUdpEndpoint(std::string_view text, std::string_view where, int min_port) {
  const auto colon = text.rfind(':');
  HATTR_THROW_UNLESS(colon != std::string_view::npos && colon > 0,
                     "{}: expected HOST:PORT (HOST an IPv4 address or localhost), got \"{}\"", where, text);
  const std::string host(text.substr(0, colon));
  const std::string_view port_text = text.substr(colon + 1);
  UdpEndpoint out;
  in_addr address{};
  if (host == "localhost") {
    out.address = INADDR_LOOPBACK;
  } else {
    HATTR_THROW_UNLESS(::inet_pton(AF_INET, host.c_str(), &address) == 1,
                       "{}: host: expected an IPv4 address (like 127.0.0.1) or localhost, got \"{}\"", where, host);
    out.address = ntohl(address.s_addr);
  }
  int port = -1;
  const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  HATTR_THROW_UNLESS(ec == std::errc{} && end == port_text.data() + port_text.size() && port >= min_port &&
                         port <= 65535,
                     "{}: port: expected a number in [{}, 65535], got \"{}\"", where, min_port, port_text);
  out.port = static_cast<std::uint16_t>(port);
  return out;
}

UdpSocket UdpSocket::bound(const UdpEndpoint& local) {
  UdpSocket s(openSocket(local.text()));
  const sockaddr_in a = toSockaddr(local);
  if (::bind(s.fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    throw Error(fmt::format("cannot listen on {}: {}", local.text(), std::strerror(errno)));
  }
  return s;
}

UdpSocket UdpSocket::connected(const UdpEndpoint& peer) {
  UdpSocket s(openSocket(peer.text()));
  const sockaddr_in a = toSockaddr(peer);
  if (::connect(s.fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    throw Error(fmt::format("cannot address {}: {}", peer.text(), std::strerror(errno)));
  }
  s.connected_ = true;
  return s;
}

UdpSocket::UdpSocket(UdpSocket&& other) noexcept : fd_(other.fd_), connected_(other.connected_) { other.fd_ = -1; }

UdpSocket& UdpSocket::operator=(UdpSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    connected_ = other.connected_;
    clock_offset_ns_ = 0;
    other.fd_ = -1;
  }
  return *this;
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) ::close(fd_);
}

UdpEndpoint UdpSocket::localEndpoint() const {
  sockaddr_in a{};
  socklen_t length = sizeof a;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &length) != 0) {
    throw Error(fmt::format("cannot read the socket's address: {}", std::strerror(errno)));
  }
  return {ntohl(a.sin_addr.s_addr), ntohs(a.sin_port)};
}

std::int64_t monotonicArrival(std::int64_t mono_ns, std::int64_t real_ns, std::int64_t stamp_real_ns,
                              std::int64_t& offset_ns) noexcept {
  const std::int64_t offset = real_ns - mono_ns;
  const bool stepped = offset_ns != 0 && std::abs(offset - offset_ns) > UdpSocket::kMaxClockStep;
  offset_ns = offset;
  const std::int64_t age = real_ns - stamp_real_ns;
  return stepped || age < 0 ? mono_ns : mono_ns - age;
}

// recvmsg with MSG_TRUNC (the true size, so an oversized datagram is seen as such) and the
// kernel's CLOCK_REALTIME arrival stamp, moved onto CLOCK_MONOTONIC by its age unless the
// real-time clock stepped since the previous receive.
ReceiveStatus UdpSocket::receive(std::span<std::uint8_t> buffer, Received& out) noexcept {
  sockaddr_in from{};
  iovec io{buffer.data(), buffer.size()};
  alignas(cmsghdr) std::uint8_t control[CMSG_SPACE(sizeof(timespec))];
  msghdr message{};
  message.msg_name = &from;
  message.msg_namelen = sizeof from;
  message.msg_iov = &io;
  message.msg_iovlen = 1;
  message.msg_control = control;
  message.msg_controllen = sizeof control;
  const ssize_t n = ::recvmsg(fd_, &message, MSG_DONTWAIT | MSG_TRUNC);
  if (n < 0) return errno == ECONNREFUSED ? ReceiveStatus::kRefused : ReceiveStatus::kNone;
  timespec mono{};
  timespec real{};
  ::clock_gettime(CLOCK_MONOTONIC, &mono);
  ::clock_gettime(CLOCK_REALTIME, &real);
  out.arrival_ns = nsOf(mono);
  for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec stamp{};
      std::memcpy(&stamp, CMSG_DATA(c), sizeof stamp);
      out.arrival_ns = monotonicArrival(nsOf(mono), nsOf(real), nsOf(stamp), clock_offset_ns_);
    }
  }
  out.size = static_cast<std::size_t>(n);
  out.from = {ntohl(from.sin_addr.s_addr), ntohs(from.sin_port)};
  return ReceiveStatus::kPacket;
}

bool UdpSocket::send(std::span<const std::uint8_t> datagram) noexcept {
  return ::send(fd_, datagram.data(), datagram.size(), MSG_DONTWAIT | MSG_NOSIGNAL) ==
         static_cast<ssize_t>(datagram.size());
}

bool UdpSocket::sendTo(std::span<const std::uint8_t> datagram, const UdpEndpoint& to) noexcept {
  const sockaddr_in a = toSockaddr(to);
  return ::sendto(fd_, datagram.data(), datagram.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                  reinterpret_cast<const sockaddr*>(&a), sizeof a) == static_cast<ssize_t>(datagram.size());
}

bool UdpSocket::waitReadable(std::int64_t timeout_ns) const noexcept {
  pollfd p{fd_, POLLIN, 0};
  const int ms = static_cast<int>(std::max<std::int64_t>(0, (timeout_ns + 999'999) / 1'000'000));
  return ::poll(&p, 1, ms) > 0;
}

}  // namespace hattr::wire
