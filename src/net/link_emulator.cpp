#include "hattr/net/link_emulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"

namespace hattr::net {

void LinkConditions::validate() const {
  const auto check_time = [](const char* name, double value) {
    HATTR_THROW_UNLESS(std::isfinite(value) && value >= 0.0 && value <= 10.0,
                       "link conditions: {}: expected a time in [0, 10] s, got {}", name, value);
  };
  const auto check_probability = [](const char* name, double value) {
    HATTR_THROW_UNLESS(std::isfinite(value) && value >= 0.0 && value <= 1.0,
                       "link conditions: {}: expected a probability in [0, 1], got {}", name, value);
  };
  check_time("delay", delay_s);
  check_time("jitter", jitter_s);
  check_time("reorder_extra", reorder_extra_s);
  check_probability("loss", loss);
  check_probability("reorder", reorder);
  check_probability("duplicate", duplicate);
}

LinkEmulator::LinkEmulator(const LinkConditions& conditions, std::size_t capacity)
    : conditions_(conditions), pool_(capacity), random_(conditions.seed) {
  conditions_.validate();
  HATTR_THROW_UNLESS(capacity > 0, "link emulator: capacity must be positive");
}

void LinkEmulator::enqueue(std::span<const std::uint8_t> datagram, std::int64_t due_ns, std::uint64_t order) noexcept {
  if (count_ == pool_.size() || datagram.size() > wire::kMaxPacketSize) {
    ++stats_.overflow;
    return;
  }
  InFlight& slot = pool_[count_++];
  slot.due_ns = due_ns;
  slot.order = order;
  slot.size = datagram.size();
  std::memcpy(slot.bytes.data(), datagram.data(), datagram.size());
}

// Every random draw happens here, in send order, so a seed gives the same link every run.
void LinkEmulator::send(std::span<const std::uint8_t> datagram, std::int64_t now_ns) noexcept {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  ++stats_.sent;
  const std::uint64_t order = next_order_++;
  const bool lost = uniform(random_) < conditions_.loss;
  const double jitter = uniform(random_) * conditions_.jitter_s;
  const bool held_back = uniform(random_) < conditions_.reorder;
  const bool duplicated = uniform(random_) < conditions_.duplicate;
  const double second_jitter = uniform(random_) * conditions_.jitter_s;
  if (lost) {
    ++stats_.lost;
    return;
  }
  const std::int64_t due = now_ns + units::secondsToNanoseconds(conditions_.delay_s + jitter + (held_back ? conditions_.reorder_extra_s : 0.0));
  enqueue(datagram, due, order);
  if (duplicated) {
    ++stats_.duplicated;
    enqueue(datagram, due + units::secondsToNanoseconds(second_jitter), order);
  }
}

bool LinkEmulator::receive(std::int64_t now_ns, std::span<std::uint8_t> out, std::size_t& size) noexcept {
  // The earliest due datagram (ties: the earlier sent).
  std::size_t best = count_;
  for (std::size_t i = 0; i < count_; ++i) {
    if (pool_[i].due_ns > now_ns) continue;
    if (best == count_ || pool_[i].due_ns < pool_[best].due_ns ||
        (pool_[i].due_ns == pool_[best].due_ns && pool_[i].order < pool_[best].order)) {
      best = i;
    }
  }
  if (best == count_) return false;
  const InFlight& slot = pool_[best];
  size = std::min(slot.size, out.size());
  std::memcpy(out.data(), slot.bytes.data(), size);
  if (delivered_any_ && slot.order < newest_delivered_) ++stats_.reordered;
  newest_delivered_ = delivered_any_ ? std::max(newest_delivered_, slot.order) : slot.order;
  delivered_any_ = true;
  ++stats_.delivered;
  pool_[best] = pool_[--count_];  // swap-remove: order in the pool does not matter
  return true;
}

std::int64_t LinkEmulator::nextDue() const noexcept {
  std::int64_t due = std::numeric_limits<std::int64_t>::max();
  for (std::size_t i = 0; i < count_; ++i) due = std::min(due, pool_[i].due_ns);
  return due;
}

// ---- The UDP relay ----------------------------------------------------------------------

LinkRelay::LinkRelay(const std::string& listen, const std::string& forward, const LinkConditions& to_forward,
                     const LinkConditions& to_sender)
    : front_(wire::UdpSocket::bound(wire::parseUdpEndpoint(listen, "link relay --listen", 0))),
      back_(wire::UdpSocket::connected(wire::parseUdpEndpoint(forward, "link relay --forward"))),
      endpoint_(front_.localEndpoint()),
      to_forward_(to_forward),
      to_sender_(to_sender) {
  thread_ = std::thread([this] { run(); });
}

LinkRelay::~LinkRelay() { stop(); }

void LinkRelay::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

LinkStats LinkRelay::forwardStats() const { return to_forward_.stats(); }
LinkStats LinkRelay::backStats() const { return to_sender_.stats(); }

// Poll both sockets, pass what arrives through the emulators, send what falls due; sleep a
// little when idle (the relay is a test rig, not a servo loop).
void LinkRelay::run() {
  wire::PacketBuffer buffer{};
  while (!stop_.load(std::memory_order_acquire)) {
    const std::int64_t now = wire::monotonicNs();
    wire::Received got;
    bool busy = false;
    while (front_.receive(buffer, got) == wire::ReceiveStatus::kPacket) {
      sender_ = got.from;
      has_sender_ = true;
      to_forward_.send(std::span(buffer.data(), std::min(got.size, buffer.size())), now);
      busy = true;
    }
    while (back_.receive(buffer, got) == wire::ReceiveStatus::kPacket) {
      to_sender_.send(std::span(buffer.data(), std::min(got.size, buffer.size())), now);
      busy = true;
    }
    std::size_t size = 0;
    while (to_forward_.receive(now, buffer, size)) (void)back_.send(std::span(buffer.data(), size));
    while (to_sender_.receive(now, buffer, size)) {
      if (has_sender_) (void)front_.sendTo(std::span(buffer.data(), size), sender_);
    }
    if (!busy) std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
}

}  // namespace hattr::net
