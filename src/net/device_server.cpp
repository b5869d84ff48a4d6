#include "hattr/net/device_server.hpp"

#include <algorithm>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/wire/datagram_link.hpp"
#include "hattr/wire/link_session.hpp"

namespace hattr::net {
// Named, not anonymous: DeviceServer::Impl holds these, and GCC's -Wsubobject-linkage (an error
// under CI's -Werror) refuses a class with external linkage holding types of an anonymous
// namespace in any file but the one compiled, which this file is not in a unity batch.
namespace server_parts {

constexpr double kLiftHeight_m = 0.003;   // a released hand holds the pen at least this high

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

/// What each WELCOME offers: the served device and the server's timing.
wire::WelcomePayload offerOf(const DeviceServerConfig& config, const device::Device& device, const servo::ServoLoop& loop) {
  wire::WelcomePayload offer;
  offer.rate_hz = 1e9 / static_cast<double>(loop.period().count());
  offer.session_timeout_ns = config.session_timeout.count();
  offer.command_timeout_ns = config.command_timeout.count();
  offer.capabilities = device.capabilities();
  offer.limits = device.limits();
  return offer;
}

/// The drain budget of a tick: a quarter of the period, at most a quarter millisecond.
wire::LinkSessionTiming timingOf(const DeviceServerConfig& config, const servo::ServoLoop& loop) {
  wire::LinkSessionTiming timing;
  timing.session_timeout_ns = config.session_timeout.count();
  timing.drain_budget_ns = std::min<std::int64_t>(timing.drain_budget_ns, loop.period().count() / 4);
  return timing;
}

}  // namespace server_parts

/// The server's stage in its own servo loop: network in, STATE out, the client's force back.
/// The session itself (handshake, checks, timeouts) is wire::ResponderLinkSession's.
class DeviceServer::Impl final : public GuidanceController {
 public:
  explicit Impl(DeviceServerConfig config)
      : config_(std::move(config)),
        served_(device::openDevice(config_.device_uri, &hand_)),
        loop_(served_, servo::ServoConfig{.rate_hz = server_parts::rateFor(config_, served_),
                                          .realtime = config_.realtime,
                                          .sample_ring_capacity = 1024}),
        link_(wire::UdpSocket::bound(wire::parseUdpEndpoint(config_.listen, "device server --listen", 0)),
              wire::UdpDatagramLink::Clock::kMonotonic),
        session_(checkedKey(config_), wire::PacketType::kCommand, link_, server_parts::offerOf(config_, served_, loop_),
                 server_parts::timingOf(config_, loop_)) {
    loop_.setGuidance(this);
  }

  Vec3 compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept override;

  void stop() {
    loop_.stop();
    session_.close(wire::monotonicNs());
    endSession();
  }

  DeviceServerConfig config_;
  server_parts::RemoteHand hand_;
  server_parts::ServedDevice served_;
  servo::ServoLoop loop_;
  wire::UdpDatagramLink link_;
  wire::ResponderLinkSession session_;

  // The client's newest command (servo thread).
  std::uint64_t generation_ = 0;  // the session the command state belongs to
  bool have_command_ = false;
  bool timed_out_ = false;
  bool ramp_pending_ = false;     // a ramp restart the loop's mailbox had no room for yet
  Vec3 command_force_ = Vec3::Zero();
  std::int64_t command_arrival_ns_ = 0;
  std::int64_t command_sent_ns_ = 0;
  std::uint64_t command_sequence_ = 0;

  // Readable from any thread.
  server_parts::AtomicVec3 commanded_;
  std::atomic<std::uint64_t> command_timeouts_{0};
  std::atomic<std::uint64_t> states_sent_{0};

 private:
  static const wire::AuthKey& checkedKey(const DeviceServerConfig& config) {
    HATTR_THROW_UNLESS(config.command_timeout.count() > 0 && config.session_timeout > config.command_timeout,
                       "device server: expected 0 < command timeout < session timeout, got {} ns and {} ns",
                       config.command_timeout.count(), config.session_timeout.count());
    return config.key;
  }
  void followSession() noexcept;
  void takeCommand() noexcept;
  void endSession() noexcept {
    have_command_ = false;
    hand_.release();
  }
  void restartRamp() noexcept {
    ramp_pending_ = !loop_.post({.type = servo::ServoCommand::Type::kRestartRamp});
  }
  void sendState(const PenState& pen, bool no_command) noexcept;
};

// A new session starts from zero force with a ramp; an ended one releases the remote hand. A
// fault latched by the safety path (a device error) stays latched: no client clears it.
void DeviceServer::Impl::followSession() noexcept {
  const std::uint64_t generation = session_.generation();
  if (generation != generation_) {
    generation_ = generation;
    have_command_ = false;
    timed_out_ = false;
    restartRamp();
  } else if (ramp_pending_) {
    restartRamp();
  }
  if (!session_.live() && have_command_) endSession();
}

void DeviceServer::Impl::takeCommand() noexcept {
  wire::Packet packet;
  std::int64_t arrival_ns = 0;
  if (!session_.takeData(packet, arrival_ns)) return;
  const auto& command = std::get<wire::CommandPayload>(packet.payload);
  command_force_ = command.f_on_pen_W;
  commanded_.store(command_force_);
  have_command_ = true;
  command_arrival_ns_ = arrival_ns;
  command_sent_ns_ = packet.header.sender_time_ns;
  command_sequence_ = packet.header.sequence;
  if (command.has_hand) hand_.set(command.hand);
}

// One tick: the session's network work, the newest command, the pen to the client, the
// client's force (zero without a session or a fresh command). The loop's safety path clamps
// what follows.
Vec3 DeviceServer::Impl::compute(const PenState& pen, const ContactForces& /*contact*/, double /*dt_s*/) noexcept {
  const std::int64_t now = wire::monotonicNs();
  session_.pump(now);
  followSession();
  if (!session_.live()) return Vec3::Zero();
  takeCommand();

  // The client's force while its commands are fresh; after a timeout, zero, then a ramp.
  Vec3 force = Vec3::Zero();
  bool no_command = true;
  if (have_command_ && now - command_arrival_ns_ <= config_.command_timeout.count()) {
    force = command_force_;
    no_command = false;
    if (timed_out_) {
      timed_out_ = false;
      restartRamp();
    }
  } else if (have_command_ && !timed_out_) {
    timed_out_ = true;
    command_timeouts_.fetch_add(1, std::memory_order_relaxed);
  }
  // No stream before the client proves the session with a COMMAND.
  if (session_.confirmed()) sendState(pen, no_command);
  return force;
}

void DeviceServer::Impl::sendState(const PenState& pen, bool no_command) noexcept {
  wire::StatePayload state;
  state.pen = pen;
  state.f_applied_W = served_.lastWritten();
  state.device_status = served_.lastRead();
  state.server_flags = (no_command ? wire::kServerNoCommand : 0u) |
                       (loop_.safety().fault() != servo::SafetyFault::kNone ? wire::kServerSafetyFault : 0u);
  const std::int64_t send_ns = wire::monotonicNs();
  if (have_command_) {
    state.echo_sender_time_ns = command_sent_ns_;
    state.echo_sequence = command_sequence_;
    state.hold_ns = std::clamp<std::int64_t>(send_ns - command_arrival_ns_, 0, wire::kMaxHoldNs);
  }
  if (session_.send(state, send_ns)) states_sent_.fetch_add(1, std::memory_order_relaxed);
}

DeviceServer::DeviceServer(DeviceServerConfig config)
    : impl_(std::make_unique<Impl>(std::move(config))), endpoint_(impl_->link_.localEndpoint()) {}

DeviceServer::~DeviceServer() { stop(); }

void DeviceServer::start() { impl_->loop_.start(); }

void DeviceServer::stop() { impl_->stop(); }

DeviceServerStats DeviceServer::stats() const {
  const Impl& i = *impl_;
  const wire::LinkSessionStats session = i.session_.stats();
  DeviceServerStats s;
  s.sessions = session.sessions;
  s.session_timeouts = session.timeouts;
  s.byes = session.byes_received;
  s.busy_refusals = session.busy;
  s.cookies_sent = session.cookies;
  s.commands_applied = session.data_received;
  s.command_timeouts = i.command_timeouts_.load();
  s.states_sent = i.states_sent_.load();
  s.drops = session.drops;
  const auto& c = i.loop_.counters();
  s.ticks = c.ticks.load();
  s.overruns = c.overruns.load();
  s.stalls = c.stalls.load();
  s.faults = c.faults.load();
  return s;
}

bool DeviceServer::sessionLive() const noexcept { return impl_->session_.live(); }
Vec3 DeviceServer::commandedForce() const noexcept { return impl_->commanded_.load(); }
Vec3 DeviceServer::appliedForce() const noexcept { return impl_->served_.applied(); }
servo::ServoLoop& DeviceServer::loop() noexcept { return impl_->loop_; }
device::Device& DeviceServer::device() noexcept { return impl_->served_.inner(); }

}  // namespace hattr::net
