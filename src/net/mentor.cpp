#include "hattr/net/mentor.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::net {
namespace {

using device::net::DropReason;
using device::net::PacketType;

constexpr std::size_t kMaxDrain = 32;  // datagrams handled per tick at most
constexpr double kPi = 3.141592653589793;

std::int64_t toNs(double seconds) noexcept { return static_cast<std::int64_t>(std::llround(seconds * 1e9)); }

void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

/// Only the paper plane: the person keeps the pen's height and pressure.
Vec3 inPlane(const Vec3& v) noexcept { return {v.x(), v.y(), 0.0}; }

}  // namespace

std::string_view couplingName(Coupling coupling) noexcept {
  switch (coupling) {
    case Coupling::kObserve: return "observe";
    case Coupling::kPosition: return "position";
    case Coupling::kForce: return "force";
    case Coupling::kBilateral: return "bilateral";
  }
  return "unknown";
}

Coupling parseCoupling(std::string_view text) {
  for (const Coupling c : {Coupling::kObserve, Coupling::kPosition, Coupling::kForce, Coupling::kBilateral}) {
    if (text == couplingName(c)) return c;
  }
  throw InputError(fmt::format("coupling: expected observe, position, force or bilateral, got \"{}\"", text));
}

std::string_view roleName(MentorRole role) noexcept { return role == MentorRole::kLeader ? "leader" : "follower"; }

void MentorConfig::validate() const {
  const auto check = [](const char* name, double value, double lo, double hi) {
    HATTR_THROW_UNLESS(std::isfinite(value) && value >= lo && value <= hi, "mentoring: {}: expected [{}, {}], got {}",
                       name, lo, hi, value);
  };
  check("hold_s", hold_s, 5e-4, 1.0);
  check("ramp_s", ramp_s, 0.0, 5.0);
  check("session_timeout_s", session_timeout_s, 0.01, 60.0);
  check("hello_interval_s", hello_interval_s, 0.001, 5.0);
  check("deadband (Weber fraction)", deadband, 0.0, 1.0);
  check("deadband position [m]", deadband_position_m, 0.0, 0.01);
  check("heartbeat_s", heartbeat_s, 0.001, 1.0);
  HATTR_THROW_UNLESS(heartbeat_s < hold_s, "mentoring: heartbeat_s: expected less than hold_s = {} s (or the link "
                     "drops between PEERs), got {}", hold_s, heartbeat_s);
  check("position Kp [N/m]", gains.position_kp_N_per_m, 0.0, 1e5);
  check("position Kd [N·s/m]", gains.position_kd_N_s_per_m, 0.0, 1e4);
  check("force Kp", gains.force_kp, 0.0, 100.0);
  check("force Kd [s]", gains.force_kd_s, 0.0, 10.0);
  check("force derivative cutoff [Hz]", gains.force_derivative_cutoff_hz, 0.1, 1e4);
  check("bilateral K [N/m]", gains.bilateral_k_N_per_m, 0.0, 1e5);
  check("bilateral B [N·s/m]", gains.bilateral_b_N_s_per_m, 0.0, 1e4);
  HATTR_THROW_UNLESS(role == MentorRole::kLeader || leader.port != 0,
                     "mentoring: the follower needs the leader's address (HOST:PORT)");
}

// ---- Links ------------------------------------------------------------------------------

bool UdpDatagramLink::receive(std::int64_t /*now_ns*/, device::net::PacketBuffer& buffer, std::size_t& size,
                              device::net::UdpEndpoint& from) noexcept {
  device::net::Received got;
  // A refusal (ICMP: nothing listens at the peer) is no datagram; the missing PEERs say the rest.
  while (true) {
    const auto status = socket_.receive(buffer, got);
    if (status == device::net::ReceiveStatus::kNone) return false;
    if (status == device::net::ReceiveStatus::kPacket) break;
  }
  size = got.size;
  from = got.from;
  return true;
}

bool UdpDatagramLink::send(std::int64_t /*now_ns*/, std::span<const std::uint8_t> datagram,
                           const device::net::UdpEndpoint& to) noexcept {
  return socket_.sendTo(datagram, to);
}

EmulatedLinkPair::EmulatedLinkPair(const LinkConditions& zero_to_one, const LinkConditions& one_to_zero)
    : zero_to_one_(zero_to_one), one_to_zero_(one_to_zero), end0_(one_to_zero_, zero_to_one_, 1), end1_(zero_to_one_, one_to_zero_, 0) {}

device::net::UdpEndpoint EmulatedLinkPair::addressOf(int index) noexcept {
  return {.address = 0x7F000001u, .port = static_cast<std::uint16_t>(40000 + index)};
}

bool EmulatedLinkPair::End::receive(std::int64_t now_ns, device::net::PacketBuffer& buffer, std::size_t& size,
                                    device::net::UdpEndpoint& from) noexcept {
  if (!in_.receive(now_ns, buffer, size)) return false;
  from = addressOf(peer_index_);
  return true;
}

bool EmulatedLinkPair::End::send(std::int64_t now_ns, std::span<const std::uint8_t> datagram,
                                 const device::net::UdpEndpoint& /*to*/) noexcept {
  out_.send(datagram, now_ns);
  return true;
}

// ---- The coupling -----------------------------------------------------------------------

MentorCoupling::MentorCoupling(const MentorConfig& config, DatagramLink& link) : config_(config), link_(link) {
  config_.validate();
  device::net::initCrypto();
  if (config_.role == MentorRole::kFollower) other_ = config_.leader;
}

void MentorCoupling::send(const device::net::Payload& payload, const device::net::UdpEndpoint& to,
                          std::int64_t now_ns) noexcept {
  const device::net::Packet packet{{.session_id = session_id_, .sequence = ++send_sequence_, .sender_time_ns = now_ns},
                                   payload};
  (void)link_.send(now_ns, std::span(tx_.data(), device::net::encodePacket(packet, config_.key, tx_)), to);
}

void MentorCoupling::sayHello(std::int64_t now_ns) noexcept {
  if (now_ns - last_hello_ns_ < toNs(config_.hello_interval_s)) return;
  last_hello_ns_ = now_ns;
  // One nonce per attempt: retries repeat it, so a WELCOME that takes longer than the retry
  // interval (a long round trip) still answers the attempt.
  if (!hello_pending_) random_.fill(nonce_);
  hello_pending_ = true;
  const device::net::Packet hello{{.session_id = 0, .sequence = 0, .sender_time_ns = now_ns},
                                  device::net::HelloPayload{nonce_}};
  (void)link_.send(now_ns, std::span(tx_.data(), device::net::encodePacket(hello, config_.key, tx_)), other_);
}

// The leader takes one follower; another gets BUSY; a new HELLO from the same follower starts over.
void MentorCoupling::onHello(const device::net::Nonce& nonce, const device::net::UdpEndpoint& from,
                             std::int64_t now_ns) noexcept {
  if (config_.role != MentorRole::kLeader) {
    drops_.count(DropReason::kUnexpected);
    return;
  }
  const bool live = session_ && now_ns - last_heard_ns_ <= toNs(config_.session_timeout_s);
  if (live && from == other_ && nonce == nonce_) {  // a retried HELLO: welcome again
    const device::net::Packet welcome{{.session_id = session_id_, .sequence = 0, .sender_time_ns = now_ns},
                                      device::net::WelcomePayload{.client_nonce = nonce, .rate_hz = 1.0,
                                                                  .session_timeout_ns = toNs(config_.session_timeout_s),
                                                                  .command_timeout_ns = toNs(config_.hold_s)}};
    (void)link_.send(now_ns, std::span(tx_.data(), device::net::encodePacket(welcome, config_.key, tx_)), from);
    return;
  }
  if (live && from != other_) {
    const device::net::Packet busy{{.session_id = 0, .sequence = 0, .sender_time_ns = now_ns},
                                   device::net::BusyPayload{nonce}};
    (void)link_.send(now_ns, std::span(tx_.data(), device::net::encodePacket(busy, config_.key, tx_)), from);
    bump(busy_refusals_);
    drops_.count(DropReason::kBusy);
    return;
  }
  // A new session: a fresh id, so packets of an old one are never accepted.
  session_ = true;
  session_id_ = random_.nextNonZero();
  nonce_ = nonce;
  other_ = from;
  peer_sequence_.reset();
  send_sequence_ = 0;
  have_sent_ = false;
  have_other_ = false;
  last_heard_ns_ = now_ns;
  bump(sessions_);
  const device::net::Packet welcome{{.session_id = session_id_, .sequence = 0, .sender_time_ns = now_ns},
                                    device::net::WelcomePayload{.client_nonce = nonce, .rate_hz = 1.0,
                                                                .session_timeout_ns = toNs(config_.session_timeout_s),
                                                                .command_timeout_ns = toNs(config_.hold_s)}};
  (void)link_.send(now_ns, std::span(tx_.data(), device::net::encodePacket(welcome, config_.key, tx_)), from);
}

void MentorCoupling::handle(const device::net::Packet& packet, const device::net::UdpEndpoint& from,
                            std::int64_t now_ns) noexcept {
  const device::net::PacketHeader& h = packet.header;
  switch (h.type) {
    case PacketType::kHello: onHello(std::get<device::net::HelloPayload>(packet.payload).client_nonce, from, now_ns); return;
    case PacketType::kWelcome: {
      const auto& welcome = std::get<device::net::WelcomePayload>(packet.payload);
      if (config_.role != MentorRole::kFollower || from != other_ || welcome.client_nonce != nonce_) {
        drops_.count(DropReason::kWrongSession);
        return;
      }
      if (!session_ || session_id_ != h.session_id) {
        session_ = true;
        session_id_ = h.session_id;
        peer_sequence_.reset();
        send_sequence_ = 0;
        have_sent_ = false;
        have_other_ = false;
        last_heard_ns_ = now_ns;
        bump(sessions_);
      }
      hello_pending_ = false;
      refused_.store(false, std::memory_order_relaxed);
      return;
    }
    case PacketType::kBusy: {
      const auto& busy = std::get<device::net::BusyPayload>(packet.payload);
      if (config_.role == MentorRole::kFollower && from == other_ && busy.client_nonce == nonce_) {
        refused_.store(true, std::memory_order_relaxed);
      } else {
        drops_.count(DropReason::kWrongSession);
      }
      return;
    }
    case PacketType::kPeer:
    case PacketType::kBye: break;
    default: drops_.count(DropReason::kUnexpected); return;
  }
  // PEER and BYE: the live session's, from the other station, newer than any accepted.
  if (!session_ || h.session_id != session_id_ || from != other_) {
    drops_.count(DropReason::kWrongSession);
    return;
  }
  DropReason why{};
  if (!peer_sequence_.accept(h.sequence, why)) {
    drops_.count(why);
    return;
  }
  last_heard_ns_ = now_ns;
  if (h.type == PacketType::kBye) {  // a normal end: the link goes down without a fault
    if (session_) bump(goodbyes_);
    session_ = false;
    have_other_ = false;
    link_up_ = false;
    return;
  }
  other_state_ = std::get<device::net::PeerPayload>(packet.payload);
  other_arrival_ns_ = now_ns;
  other_sender_ns_ = h.sender_time_ns;
  have_other_ = true;
  bump(peers_received_);
  // Round trip: our echoed time, less the time the other held it.
  if (other_state_.echo_sender_time_ns > 0) {
    const double rtt = static_cast<double>(now_ns - other_state_.echo_sender_time_ns - other_state_.hold_ns) * 1e-9;
    if (rtt >= 0.0) rtt_snapshot_.store(rtt, std::memory_order_relaxed);
  }
}

void MentorCoupling::drain(std::int64_t now_ns) noexcept {
  for (std::size_t i = 0; i < kMaxDrain; ++i) {
    std::size_t size = 0;
    device::net::UdpEndpoint from;
    if (!link_.receive(now_ns, rx_, size, from)) return;
    if (size > rx_.size()) {
      drops_.count(DropReason::kBadSize);
      continue;
    }
    device::net::Packet packet;
    DropReason why{};
    if (!device::net::decodePacket(std::span(rx_.data(), size), config_.key, packet, why)) {
      drops_.count(why);
      continue;
    }
    handle(packet, from, now_ns);
  }
}

// The raw coupling force on this station's pen, before the fade and the passivity controller.
Vec3 MentorCoupling::couplingForce(const PenState& pen, const ContactForces& contact, double dt_s) noexcept {
  const CouplingGains& g = config_.gains;
  const bool follower = config_.role == MentorRole::kFollower;
  const Vec3 dp = other_state_.p_WT - pen.p_WT;
  const Vec3 dv = other_state_.v_WT - pen.v_WT;
  switch (activeCoupling()) {
    case Coupling::kObserve: return Vec3::Zero();
    case Coupling::kPosition:
      return follower ? inPlane(g.position_kp_N_per_m * dp + g.position_kd_N_s_per_m * dv) : Vec3(Vec3::Zero());
    case Coupling::kBilateral: return inPlane(g.bilateral_k_N_per_m * dp + g.bilateral_b_N_s_per_m * dv);
    case Coupling::kForce: {
      if (!follower) return Vec3::Zero();
      // ALPHA live: the leader's force on the paper against ours, with a filtered rate.
      const Vec3 error = other_state_.f_user_W - contact.f_on_paper_W;
      if (have_error_ && dt_s > 0.0) {
        const double a = 1.0 - std::exp(-2.0 * kPi * g.force_derivative_cutoff_hz * dt_s);
        error_rate_ += a * ((error - last_error_) / dt_s - error_rate_);
      }
      last_error_ = error;
      have_error_ = true;
      if (!contact.in_contact) return Vec3::Zero();
      return g.force_kp * error + g.force_kd_s * error_rate_;
    }
  }
  return Vec3::Zero();
}

// Time-domain passivity controller at this port: the power the coupling gives the person is
// cut, by a damper along the pen's velocity, so that the energy given never exceeds the energy
// the other station's person put in (as last heard). The cut never exceeds the force's own
// component along the velocity, so it cannot push back.
Vec3 MentorCoupling::passive(const Vec3& force, const Vec3& v_WT, double dt_s) noexcept {
  const double power = force.dot(v_WT);
  const double allowance = other_state_.energy_in_J - energy_out_J_;
  const double v2 = v_WT.squaredNorm();
  if (power <= 0.0 || power * dt_s <= allowance || v2 <= 0.0 || dt_s <= 0.0) return force;
  const double excess = power * dt_s - std::max(allowance, 0.0);
  const double alpha = excess / (dt_s * v2);
  dissipated_J_ += excess;
  return force - alpha * v_WT;
}

Vec3 MentorCoupling::compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept {
  const std::int64_t now_ns = toNs(pen.t_s);
  drain(now_ns);

  // The session: the follower says HELLO until welcomed; a silent one ends.
  if (session_ && now_ns - last_heard_ns_ > toNs(config_.session_timeout_s)) {
    session_ = false;
    have_other_ = false;
  }
  if (!session_ && config_.role == MentorRole::kFollower) sayHello(now_ns);

  // The link: fresh PEERs; a lost link zeroes the force at once and fades in when back.
  const bool up = session_ && have_other_ && now_ns - other_arrival_ns_ <= toNs(config_.hold_s);
  if (link_up_ && !up) bump(link_faults_);
  link_up_ = up;
  Vec3 force = Vec3::Zero();
  if (up) {
    ramp_ = config_.ramp_s > 0.0 ? std::min(1.0, ramp_ + dt_s / config_.ramp_s) : 1.0;
    force = ramp_ * couplingForce(pen, contact, dt_s);
    if (config_.passivity && activeCoupling() == Coupling::kBilateral) force = passive(force, pen.v_WT, dt_s);
  } else {
    ramp_ = 0.0;
    have_error_ = false;
    error_rate_.setZero();
  }
  if (!force.allFinite()) force.setZero();

  // This port's energy: what the coupling gave the person, and what the person put in.
  const double power = force.dot(pen.v_WT) * dt_s;
  if (power > 0.0) energy_out_J_ += power;
  if (power < 0.0) energy_in_J_ -= power;

  // Tell the other station. The leader streams only once the follower has sent an authentic
  // PEER of this session, so a replayed HELLO never starts a stream.
  if (session_ && (config_.role == MentorRole::kFollower || have_other_)) {
    device::net::PeerPayload out;
    out.t_s = pen.t_s;
    out.p_WT = pen.p_WT;
    out.v_WT = pen.v_WT;
    out.f_user_W = contact.f_on_paper_W;
    out.f_coupling_W = force;
    out.energy_in_J = energy_in_J_;
    out.energy_out_J = energy_out_J_;
    out.echo_sender_time_ns = have_other_ ? other_sender_ns_ : 0;
    out.hold_ns = have_other_ ? now_ns - other_arrival_ns_ : 0;
    out.coupling = static_cast<std::uint32_t>(activeCoupling());
    out.flags = (contact.in_contact ? device::net::kPeerPenDown : 0u) | (up ? device::net::kPeerLinkUp : 0u);
    if (worthSending(out, now_ns)) {
      send(out, other_, now_ns);
      bump(peers_sent_);
      last_sent_ = out;
      last_sent_ns_ = now_ns;
      have_sent_ = true;
    } else {
      bump(peers_withheld_);
    }
  }

  // For other threads.
  if (have_other_) {
    peer_view_.write(PeerView{.valid = true, .t_s = other_state_.t_s, .p_WT = other_state_.p_WT, .v_WT = other_state_.v_WT,
                              .f_user_W = other_state_.f_user_W,
                              .pen_down = (other_state_.flags & device::net::kPeerPenDown) != 0});
  }
  session_flag_.store(session_, std::memory_order_relaxed);
  link_flag_.store(up, std::memory_order_relaxed);
  energy_in_snapshot_.store(energy_in_J_, std::memory_order_relaxed);
  energy_out_snapshot_.store(energy_out_J_, std::memory_order_relaxed);
  peer_energy_snapshot_.store(other_state_.energy_in_J, std::memory_order_relaxed);
  dissipated_snapshot_.store(dissipated_J_, std::memory_order_relaxed);
  lost_snapshot_.store(peer_sequence_.lost(), std::memory_order_relaxed);
  return force;
}

void MentorCoupling::close(std::int64_t now_ns) noexcept {
  if (!session_) return;
  send(device::net::ByePayload{}, other_, now_ns);
  session_ = false;
  session_flag_.store(false);
}

// The perceptual deadband: a change the other person could feel or see, a change of state,
// or the heartbeat that keeps the link up.
bool MentorCoupling::worthSending(const device::net::PeerPayload& out, std::int64_t now_ns) const noexcept {
  if (config_.deadband <= 0.0 || !have_sent_) return true;
  if (now_ns - last_sent_ns_ >= toNs(config_.heartbeat_s)) return true;
  if (out.flags != last_sent_.flags || out.coupling != last_sent_.coupling) return true;
  const auto beyondWeber = [k = config_.deadband](const Vec3& now, const Vec3& sent) {
    return (now - sent).norm() > k * sent.norm();
  };
  return beyondWeber(out.v_WT, last_sent_.v_WT) || beyondWeber(out.f_user_W, last_sent_.f_user_W) ||
         beyondWeber(out.f_coupling_W, last_sent_.f_coupling_W) ||
         (out.p_WT - last_sent_.p_WT).norm() > config_.deadband_position_m;
}

MentorStats MentorCoupling::stats() const noexcept {
  MentorStats s;
  s.session = session_flag_.load(std::memory_order_relaxed);
  s.link_up = link_flag_.load(std::memory_order_relaxed);
  s.sessions = sessions_.load();
  s.busy_refusals = busy_refusals_.load();
  s.refused_busy = refused_.load();
  s.link_faults = link_faults_.load();
  s.goodbyes_received = goodbyes_.load();
  s.peers_received = peers_received_.load();
  s.peers_sent = peers_sent_.load();
  s.peers_withheld = peers_withheld_.load();
  s.lost = lost_snapshot_.load();
  for (std::size_t i = 0; i < device::net::kDropReasonCount; ++i) s.drops[i] = drops_[static_cast<DropReason>(i)];
  s.energy_in_J = energy_in_snapshot_.load();
  s.energy_out_J = energy_out_snapshot_.load();
  s.peer_energy_in_J = peer_energy_snapshot_.load();
  s.dissipated_J = dissipated_snapshot_.load();
  s.rtt_s = rtt_snapshot_.load();
  return s;
}

MentorStats statsSince(const MentorStats& now, const MentorStats& before) noexcept {
  MentorStats d = now;
  d.sessions -= before.sessions;
  d.busy_refusals -= before.busy_refusals;
  d.link_faults -= before.link_faults;
  d.goodbyes_received -= before.goodbyes_received;
  d.peers_received -= before.peers_received;
  d.peers_sent -= before.peers_sent;
  d.peers_withheld -= before.peers_withheld;
  for (std::size_t i = 0; i < d.drops.size(); ++i) d.drops[i] -= before.drops[i];
  d.energy_in_J -= before.energy_in_J;
  d.energy_out_J -= before.energy_out_J;
  d.dissipated_J -= before.dissipated_J;
  return d;
}

}  // namespace hattr::net
