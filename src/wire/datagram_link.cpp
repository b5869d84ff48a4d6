#include "hattr/wire/datagram_link.hpp"

namespace hattr::wire {

bool UdpDatagramLink::receive(std::int64_t now_ns, PacketBuffer& buffer, Received& out) noexcept {
  const ReceiveStatus status = socket_.receive(buffer, out);
  if (status == ReceiveStatus::kRefused) refused_ = true;
  if (status != ReceiveStatus::kPacket) return false;
  if (clock_ == Clock::kLoop) out.arrival_ns = now_ns;
  return true;
}

bool UdpDatagramLink::send(std::int64_t /*now_ns*/, std::span<const std::uint8_t> datagram,
                           const UdpEndpoint& to) noexcept {
  return socket_.isConnected() ? socket_.send(datagram) : socket_.sendTo(datagram, to);
}

}  // namespace hattr::wire
