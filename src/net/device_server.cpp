#include "hattr/net/device_server.hpp"

#include <algorithm>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"

namespace hattr::net {
namespace {

using device::net::DropReason;
using device::net::PacketType;

constexpr std::size_t kMaxDrain = 32;     // datagrams per tick: bounds a tick's work
constexpr std::size_t kNonceMemory = 64;  // hello nonces remembered against replays
constexpr double kLiftHeight_m = 0.003;   // a released hand holds the pen at least this high

void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

/// A force readable from other threads.
class AtomicVec3 {
 public:
  void store(const Vec3& v) noexcept {
    x_.store(v.x(), std::memory_order_relaxed);
    y_.store(v.y(), std::memory_order_relaxed);
    z_.store(v.z(), std::memory_order_relaxed);
  }
  [[nodiscard]] Vec3 load() const noexcept {
    return {x_.load(std::memory_order_relaxed), y_.load(std::memory_order_relaxed), z_.load(std::memory_order_relaxed)};
  }

 private:
  std::atomic<double> x_{0.0};
  std::atomic<double> y_{0.0};
  std::atomic<double> z_{0.0};
};

/// The newest hand command a client sent: drives a simulated pen on the server (a real
/// device never asks). Read and written on the servo thread only.
class RemoteHand final : public device::HandScript {
 public:
  RemoteHand() { command_.p_target_W = device::SimulatedPenParams{}.start_position_W; }
  device::HandCommand command(double /*t_s*/) noexcept override { return command_; }
  void set(const device::HandCommand& command) noexcept { command_ = command; }
  /// Nobody writes any more: the hand lifts the pen and holds it where it is.
  void release() noexcept {
    command_.pen_down = false;
    command_.press_N = 0.0;
    command_.v_target_W.setZero();
    command_.p_target_W.z() = std::max(command_.p_target_W.z(), kLiftHeight_m);
  }

 private:
  device::HandCommand command_;
};

/// The local device as the loop sees it, remembering what was last read and written for
/// the STATE packets.
class ServedDevice final : public device::Device {
 public:
  explicit ServedDevice(std::unique_ptr<device::Device> inner) : inner_(std::move(inner)) {}
  device::DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override {
    last_read_ = inner_->read(now, out);
    return last_read_;
  }
  device::DeviceStatus write(const Vec3& f_on_pen_W) noexcept override {
    applied_.store(f_on_pen_W);
    last_written_ = f_on_pen_W;
    return inner_->write(f_on_pen_W);
  }
  const DeviceLimits& limits() const noexcept override { return inner_->limits(); }
  device::DeviceCapabilities capabilities() const noexcept override { return inner_->capabilities(); }
  const std::string& uri() const noexcept override { return inner_->uri(); }
  device::DeviceClocking clocking() const noexcept override { return inner_->clocking(); }
  void startClock(device::DeviceTickFn tick, void* context) override { inner_->startClock(tick, context); }
  void stopClock() noexcept override { inner_->stopClock(); }
  std::string faultReason() const override { return inner_->faultReason(); }

  [[nodiscard]] device::DeviceStatus lastRead() const noexcept { return last_read_; }
  [[nodiscard]] const Vec3& lastWritten() const noexcept { return last_written_; }
  [[nodiscard]] Vec3 applied() const noexcept { return applied_.load(); }
  [[nodiscard]] device::Device& inner() noexcept { return *inner_; }

 private:
  std::unique_ptr<device::Device> inner_;
  device::DeviceStatus last_read_ = device::DeviceStatus::kOk;
  Vec3 last_written_ = Vec3::Zero();
  AtomicVec3 applied_;
};

double rateFor(const DeviceServerConfig& config, const device::Device& device) {
  return config.rate_hz > 0.0 ? config.rate_hz : device.limits().nominal_rate_hz;
}

}  // namespace

/// The server's stage in its own servo loop: network in, STATE out, the client's force back.
class DeviceServer::Impl final : public GuidanceController {
 public:
  explicit Impl(DeviceServerConfig config)
      : config_(std::move(config)),
        served_(device::openDevice(config_.device_uri, &hand_)),
        loop_(served_, servo::ServoConfig{.rate_hz = rateFor(config_, served_),
                                          .realtime = config_.realtime,
                                          .sample_ring_capacity = 1024}),
        socket_(device::net::UdpSocket::bound(
            device::net::parseUdpEndpoint(config_.listen, "device server --listen", 0))) {
    HATTR_THROW_UNLESS(config_.command_timeout.count() > 0 && config_.session_timeout > config_.command_timeout,
                       "device server: expected 0 < command timeout < session timeout, got {} ns and {} ns",
                       config_.command_timeout.count(), config_.session_timeout.count());
    loop_.setGuidance(this);
  }

  Vec3 compute(const PenState& pen, const ContactForces& /*contact*/, double /*dt_s*/) noexcept override;

  void stop() {
    loop_.stop();
    if (live_.load(std::memory_order_acquire)) {
      sendBye();
      endSession();
    }
  }

  DeviceServerConfig config_;
  RemoteHand hand_;
  ServedDevice served_;
  servo::ServoLoop loop_;
  device::net::UdpSocket socket_;
  device::net::RandomStream random_;

  // Session state (servo thread).
  std::atomic<bool> live_{false};
  std::uint64_t session_id_ = 0;
  bool confirmed_ = false;  // an authentic COMMAND of this session arrived: STATEs may flow
  device::net::Nonce session_nonce_{};
  device::net::UdpEndpoint client_;
  device::net::SequenceCheck client_sequence_;
  std::uint64_t send_sequence_ = 0;
  std::int64_t last_heard_ns_ = 0;
  bool have_command_ = false;
  bool timed_out_ = false;
  Vec3 command_force_ = Vec3::Zero();
  std::int64_t command_arrival_ns_ = 0;
  std::int64_t command_sent_ns_ = 0;
  std::uint64_t command_sequence_ = 0;
  std::array<device::net::Nonce, kNonceMemory> seen_nonces_{};
  std::size_t seen_count_ = 0;
  device::net::PacketBuffer rx_buffer_{};
  device::net::PacketBuffer tx_buffer_{};

  // Readable from any thread.
  AtomicVec3 commanded_;
  std::atomic<std::uint64_t> sessions_{0};
  std::atomic<std::uint64_t> session_timeouts_{0};
  std::atomic<std::uint64_t> byes_{0};
  std::atomic<std::uint64_t> busy_refusals_{0};
  std::atomic<std::uint64_t> commands_applied_{0};
  std::atomic<std::uint64_t> command_timeouts_{0};
  std::atomic<std::uint64_t> states_sent_{0};
  device::net::DropCounters drops_;

 private:
  void handle(const device::net::Packet& packet, const device::net::Received& rx) noexcept;
  void onHello(const device::net::Nonce& nonce, const device::net::Received& rx) noexcept;
  void startSession(const device::net::Nonce& nonce, const device::net::Received& rx) noexcept;
  void endSession() noexcept {
    live_.store(false, std::memory_order_release);
    have_command_ = false;
    hand_.release();
  }
  void sendWelcome() noexcept;
  void sendBye() noexcept;
  void sendState(const PenState& pen, bool no_command) noexcept;
  void send(const device::net::Packet& packet, const device::net::UdpEndpoint& to) noexcept {
    (void)socket_.sendTo(std::span(tx_buffer_.data(), device::net::encodePacket(packet, config_.key, tx_buffer_)), to);
  }
  [[nodiscard]] bool nonceSeen(const device::net::Nonce& nonce) const noexcept {
    const std::size_t n = std::min(seen_count_, kNonceMemory);
    return std::find(seen_nonces_.begin(), seen_nonces_.begin() + static_cast<std::ptrdiff_t>(n), nonce) !=
           seen_nonces_.begin() + static_cast<std::ptrdiff_t>(n);
  }
};

// One tick: drain the socket, end a silent session, send the pen, return the client's force
// (zero without a session or a fresh command). The loop's safety path clamps what follows.
Vec3 DeviceServer::Impl::compute(const PenState& pen, const ContactForces& /*contact*/, double /*dt_s*/) noexcept {
  device::net::Received rx;
  for (std::size_t i = 0; i < kMaxDrain; ++i) {
    if (socket_.receive(rx_buffer_, rx) != device::net::ReceiveStatus::kPacket) break;
    device::net::Packet packet;
    DropReason why{};
    if (rx.size > rx_buffer_.size()) {
      drops_.count(DropReason::kBadSize);
    } else if (!device::net::decodePacket(std::span(rx_buffer_.data(), rx.size), config_.key, packet, why)) {
      drops_.count(why);
    } else {
      handle(packet, rx);
    }
  }

  const std::int64_t now = device::net::monotonicNs();
  const bool live = live_.load(std::memory_order_relaxed);
  if (live && now - last_heard_ns_ > config_.session_timeout.count()) {
    endSession();
    bump(session_timeouts_);
    return Vec3::Zero();
  }
  if (!live) return Vec3::Zero();

  // The client's force while its commands are fresh; after a timeout, zero, then a ramp.
  Vec3 force = Vec3::Zero();
  bool no_command = true;
  if (have_command_ && now - command_arrival_ns_ <= config_.command_timeout.count()) {
    force = command_force_;
    no_command = false;
    if (timed_out_) {
      timed_out_ = false;
      (void)loop_.post({.type = servo::ServoCommand::Type::kRestartRamp});
    }
  } else if (have_command_ && !timed_out_) {
    timed_out_ = true;
    bump(command_timeouts_);
  }
  // No stream before the client proves the session with a COMMAND: a replayed HELLO (from any
  // address) gets one WELCOME, never a stream of STATEs.
  if (confirmed_) sendState(pen, no_command);
  return force;
}

void DeviceServer::Impl::handle(const device::net::Packet& packet, const device::net::Received& rx) noexcept {
  const device::net::PacketHeader& h = packet.header;
  if (h.type == PacketType::kHello) {
    onHello(std::get<device::net::HelloPayload>(packet.payload).client_nonce, rx);
    return;
  }
  if (h.type != PacketType::kCommand && h.type != PacketType::kBye) {
    drops_.count(DropReason::kUnexpected);
    return;
  }
  // COMMAND and BYE: the live session's, from its client, newer than any accepted.
  if (!live_.load(std::memory_order_relaxed) || h.session_id != session_id_ || rx.from != client_) {
    drops_.count(DropReason::kWrongSession);
    return;
  }
  DropReason why{};
  if (!client_sequence_.accept(h.sequence, why)) {
    drops_.count(why);
    return;
  }
  last_heard_ns_ = rx.arrival_ns;
  if (h.type == PacketType::kBye) {
    endSession();
    bump(byes_);
    return;
  }
  const auto& command = std::get<device::net::CommandPayload>(packet.payload);
  confirmed_ = true;
  command_force_ = command.f_on_pen_W;
  commanded_.store(command_force_);
  have_command_ = true;
  command_arrival_ns_ = rx.arrival_ns;
  command_sent_ns_ = h.sender_time_ns;
  command_sequence_ = h.sequence;
  if (command.has_hand) hand_.set(command.hand);
  bump(commands_applied_);
}

// A retried hello gets its welcome again; a replayed one nothing; another client's a BUSY;
// a new one (also the same client starting over) a new session.
void DeviceServer::Impl::onHello(const device::net::Nonce& nonce, const device::net::Received& rx) noexcept {
  const bool live = live_.load(std::memory_order_relaxed);
  if (live && rx.from == client_ && nonce == session_nonce_) {
    sendWelcome();
    return;
  }
  if (nonceSeen(nonce)) {
    drops_.count(DropReason::kReplayed);
    return;
  }
  if (live && rx.from != client_) {
    const device::net::Packet busy{{.session_id = 0, .sequence = 0, .sender_time_ns = device::net::monotonicNs()},
                                   device::net::BusyPayload{nonce}};
    // Counted before the answer: a client that has read it sees the count.
    bump(busy_refusals_);
    drops_.count(DropReason::kBusy);
    send(busy, rx.from);
    return;
  }
  seen_nonces_[seen_count_++ % kNonceMemory] = nonce;
  if (live) endSession();
  startSession(nonce, rx);
}

void DeviceServer::Impl::startSession(const device::net::Nonce& nonce, const device::net::Received& rx) noexcept {
  session_id_ = random_.nextNonZero();
  session_nonce_ = nonce;
  client_ = rx.from;
  client_sequence_.reset();
  send_sequence_ = 0;
  have_command_ = false;
  timed_out_ = false;
  last_heard_ns_ = rx.arrival_ns;
  live_.store(true, std::memory_order_release);
  confirmed_ = false;
  bump(sessions_);
  // A new session starts clean: a fault latched in an earlier one is cleared, forces ramp in.
  (void)loop_.post({.type = servo::ServoCommand::Type::kClearFault});
  (void)loop_.post({.type = servo::ServoCommand::Type::kRestartRamp});
  sendWelcome();
}

void DeviceServer::Impl::sendWelcome() noexcept {
  device::net::WelcomePayload welcome;
  welcome.client_nonce = session_nonce_;
  welcome.rate_hz = 1e9 / static_cast<double>(loop_.period().count());
  welcome.session_timeout_ns = config_.session_timeout.count();
  welcome.command_timeout_ns = config_.command_timeout.count();
  welcome.capabilities = served_.capabilities();
  welcome.limits = served_.limits();
  send({{.session_id = session_id_, .sequence = ++send_sequence_, .sender_time_ns = device::net::monotonicNs()},
        welcome},
       client_);
}

void DeviceServer::Impl::sendBye() noexcept {
  send({{.session_id = session_id_, .sequence = ++send_sequence_, .sender_time_ns = device::net::monotonicNs()},
        device::net::ByePayload{}},
       client_);
}

void DeviceServer::Impl::sendState(const PenState& pen, bool no_command) noexcept {
  device::net::StatePayload state;
  state.pen = pen;
  state.f_applied_W = served_.lastWritten();
  state.device_status = served_.lastRead();
  state.server_flags = (no_command ? device::net::kServerNoCommand : 0u) |
                       (loop_.safety().fault() != servo::SafetyFault::kNone ? device::net::kServerSafetyFault : 0u);
  const std::int64_t send_ns = device::net::monotonicNs();
  if (have_command_) {
    state.echo_sender_time_ns = command_sent_ns_;
    state.echo_sequence = command_sequence_;
    state.hold_ns = std::max<std::int64_t>(0, send_ns - command_arrival_ns_);
  }
  send({{.session_id = session_id_, .sequence = ++send_sequence_, .sender_time_ns = send_ns}, state}, client_);
  bump(states_sent_);
}

DeviceServer::DeviceServer(DeviceServerConfig config)
    : impl_(std::make_unique<Impl>(std::move(config))), endpoint_(impl_->socket_.localEndpoint()) {}

DeviceServer::~DeviceServer() { stop(); }

void DeviceServer::start() { impl_->loop_.start(); }

void DeviceServer::stop() { impl_->stop(); }

DeviceServerStats DeviceServer::stats() const {
  const Impl& i = *impl_;
  DeviceServerStats s;
  s.sessions = i.sessions_.load();
  s.session_timeouts = i.session_timeouts_.load();
  s.byes = i.byes_.load();
  s.busy_refusals = i.busy_refusals_.load();
  s.commands_applied = i.commands_applied_.load();
  s.command_timeouts = i.command_timeouts_.load();
  s.states_sent = i.states_sent_.load();
  for (std::size_t r = 0; r < device::net::kDropReasonCount; ++r) s.drops[r] = i.drops_[static_cast<DropReason>(r)];
  const auto& c = i.loop_.counters();
  s.ticks = c.ticks.load();
  s.overruns = c.overruns.load();
  s.stalls = c.stalls.load();
  s.faults = c.faults.load();
  return s;
}

bool DeviceServer::sessionLive() const noexcept { return impl_->live_.load(std::memory_order_acquire); }
Vec3 DeviceServer::commandedForce() const noexcept { return impl_->commanded_.load(); }
Vec3 DeviceServer::appliedForce() const noexcept { return impl_->served_.applied(); }
servo::ServoLoop& DeviceServer::loop() noexcept { return impl_->loop_; }
device::Device& DeviceServer::device() noexcept { return impl_->served_.inner(); }

}  // namespace hattr::net
