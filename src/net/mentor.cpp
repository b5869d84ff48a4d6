#include "hattr/net/mentor.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/wire/link_session.hpp"

namespace hattr::net {
namespace {

constexpr double kPi = 3.141592653589793;

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
  check("rate_hz", rate_hz, 1.0, 10'000.0);
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

EmulatedLinkPair::EmulatedLinkPair(const LinkConditions& zero_to_one, const LinkConditions& one_to_zero)
    : zero_to_one_(zero_to_one), one_to_zero_(one_to_zero), end0_(one_to_zero_, zero_to_one_, 1), end1_(zero_to_one_, one_to_zero_, 0) {}

wire::UdpEndpoint EmulatedLinkPair::addressOf(int index) noexcept {
  return {.address = 0x7F000001u, .port = static_cast<std::uint16_t>(40000 + index)};
}

bool EmulatedLinkPair::End::receive(std::int64_t now_ns, wire::PacketBuffer& buffer, wire::Received& out) noexcept {
  if (!in_.receive(now_ns, buffer, out.size)) return false;
  out.from = addressOf(peer_index_);
  out.arrival_ns = now_ns;
  return true;
}

bool EmulatedLinkPair::End::send(std::int64_t now_ns, std::span<const std::uint8_t> datagram,
                                 const wire::UdpEndpoint& /*to*/) noexcept {
  out_.send(datagram, now_ns);
  return true;
}

// ---- The coupling -----------------------------------------------------------------------

/// One station's coupling: its session with the other station, what it last heard, the
/// coupling's filters and this port's energy.
class MentorCoupling::Impl {
 public:
  Impl(const MentorConfig& config, wire::DatagramLink& link);

  Vec3 compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept;
  void followSession(std::int64_t now_ns) noexcept;
  void takePeer(std::int64_t now_ns) noexcept;
  void tell(const PenState& pen, const ContactForces& contact, const Vec3& force, bool up, std::int64_t now_ns) noexcept;
  void publish(bool up) noexcept;
  Vec3 couplingForce(const PenState& pen, const ContactForces& contact, double dt_s) noexcept;
  Vec3 passive(const Vec3& force, const Vec3& v_WT, double dt_s) noexcept;
  /// The deadband's test: does `out` differ enough from the last PEER sent to be sent now?
  [[nodiscard]] bool worthSending(const wire::PeerPayload& out, std::int64_t now_ns) const noexcept;
  /// The follower names the coupling; the leader runs the one its follower announces.
  [[nodiscard]] Coupling activeCoupling() const noexcept {
    return config_.role == MentorRole::kLeader && have_other_ ? static_cast<Coupling>(other_state_.coupling)
                                                             : config_.coupling;
  }
  static void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

  MentorConfig config_;
  std::unique_ptr<wire::LinkSession> session_;
  wire::InitiatorLinkSession* initiator_ = nullptr;  // the follower's session (null for the leader)
  std::uint64_t generation_ = 0;
  std::uint64_t busy_seen_ = 0;
  std::uint64_t byes_seen_ = 0;

  // The other station as last heard.
  wire::PeerPayload other_state_{};
  bool have_other_ = false;
  std::int64_t other_arrival_ns_ = 0;
  std::int64_t other_sender_ns_ = 0;
  bool link_up_ = false;
  double ramp_ = 0.0;

  // Force coupling: the filtered error rate.
  Vec3 last_error_ = Vec3::Zero();
  Vec3 error_rate_ = Vec3::Zero();
  bool have_error_ = false;

  // The last PEER sent (the deadband compares with it).
  wire::PeerPayload last_sent_{};
  std::int64_t last_sent_ns_ = 0;
  bool have_sent_ = false;

  // Energy bookkeeping of this port (TDPA).
  double energy_in_J_ = 0.0;
  double energy_out_J_ = 0.0;
  double dissipated_J_ = 0.0;

  TripleBuffer<PeerView> peer_view_;
  std::atomic<bool> link_flag_{false};
  std::atomic<bool> refused_{false};
  std::atomic<std::uint64_t> link_faults_{0};
  std::atomic<std::uint64_t> peers_sent_{0};
  std::atomic<std::uint64_t> peers_withheld_{0};
  std::atomic<double> energy_in_snapshot_{0.0};
  std::atomic<double> energy_out_snapshot_{0.0};
  std::atomic<double> peer_energy_snapshot_{0.0};
  std::atomic<double> dissipated_snapshot_{0.0};
  std::atomic<double> rtt_snapshot_{0.0};
};

namespace {

wire::LinkSessionTiming mentorTiming(const MentorConfig& config) {
  wire::LinkSessionTiming timing;
  timing.session_timeout_ns = units::secondsToNanoseconds(config.session_timeout_s);
  timing.hello_retry_ns = units::secondsToNanoseconds(config.hello_interval_s);
  return timing;
}

/// What the leader's WELCOME says: its servo rate and its timeouts (a station serves no device:
/// the limits are WelcomePayload's defaults, not its pen's; docs/protocol.md).
wire::WelcomePayload leaderOffer(const MentorConfig& config) {
  wire::WelcomePayload offer;
  offer.rate_hz = config.rate_hz;
  offer.session_timeout_ns = units::secondsToNanoseconds(config.session_timeout_s);
  offer.command_timeout_ns = units::secondsToNanoseconds(config.hold_s);
  return offer;
}

}  // namespace

MentorCoupling::Impl::Impl(const MentorConfig& config, wire::DatagramLink& link) : config_(config) {
  config_.validate();
  if (config_.role == MentorRole::kLeader) {
    session_ = std::make_unique<wire::ResponderLinkSession>(config_.key, wire::PacketType::kPeer, link,
                                                            leaderOffer(config_), mentorTiming(config_));
  } else {
    auto follower = std::make_unique<wire::InitiatorLinkSession>(config_.key, wire::PacketType::kPeer, link,
                                                                 config_.leader, mentorTiming(config_));
    initiator_ = follower.get();
    session_ = std::move(follower);
  }
}

// A new session starts from nothing heard; a goodbye ends the link without a fault; the
// follower says HELLO (again every hello_interval) while it has no session, also after a BUSY.
void MentorCoupling::Impl::followSession(std::int64_t now_ns) noexcept {
  const std::uint64_t generation = session_->generation();
  if (generation != generation_) {
    generation_ = generation;
    have_other_ = false;
    have_sent_ = false;
    refused_.store(false, std::memory_order_relaxed);
  }
  const std::uint64_t byes = session_->byesReceived();
  if (byes != byes_seen_) {
    byes_seen_ = byes;
    link_up_ = false;
  }
  if (!session_->live()) have_other_ = false;
  if (initiator_ == nullptr) return;
  const std::uint64_t busy = session_->busyCount();
  if (busy != busy_seen_) {
    busy_seen_ = busy;
    refused_.store(true, std::memory_order_relaxed);
  }
  using State = wire::InitiatorLinkSession::State;
  if (!session_->live() && initiator_->state() != State::kConnecting &&
      (initiator_->lastHello_ns() == 0 || now_ns - initiator_->lastHello_ns() >= units::secondsToNanoseconds(config_.hello_interval_s))) {
    initiator_->connect(now_ns);
  }
}

void MentorCoupling::Impl::takePeer(std::int64_t now_ns) noexcept {
  wire::Packet packet;
  std::int64_t arrival_ns = 0;
  if (!session_->takeData(packet, arrival_ns)) return;
  other_state_ = std::get<wire::PeerPayload>(packet.payload);
  other_arrival_ns_ = arrival_ns;
  other_sender_ns_ = packet.header.sender_time_ns;
  have_other_ = true;
  // Round trip: our echoed time, less the time the other held it (checked: authentic is not sane).
  const std::int64_t echo = other_state_.echo_sender_time_ns;
  if (echo > 0 && echo <= now_ns && other_state_.hold_ns <= now_ns - echo) {
    rtt_snapshot_.store(static_cast<double>(now_ns - echo - other_state_.hold_ns) * 1e-9, std::memory_order_relaxed);
  }
}

// The raw coupling force on this station's pen, before the fade and the passivity controller.
Vec3 MentorCoupling::Impl::couplingForce(const PenState& pen, const ContactForces& contact, double dt_s) noexcept {
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
Vec3 MentorCoupling::Impl::passive(const Vec3& force, const Vec3& v_WT, double dt_s) noexcept {
  const double power = force.dot(v_WT);
  const double allowance = other_state_.energy_in_J - energy_out_J_;
  const double v2 = v_WT.squaredNorm();
  if (power <= 0.0 || power * dt_s <= allowance || v2 <= 0.0 || dt_s <= 0.0) return force;
  const double excess = power * dt_s - std::max(allowance, 0.0);
  const double alpha = excess / (dt_s * v2);
  dissipated_J_ += excess;
  return force - alpha * v_WT;
}

Vec3 MentorCoupling::Impl::compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept {
  const std::int64_t now_ns = units::secondsToNanoseconds(pen.t_s);
  session_->pump(now_ns);
  followSession(now_ns);
  takePeer(now_ns);

  // The link: fresh PEERs; a lost link zeroes the force at once and fades in when back.
  const bool up = session_->live() && have_other_ && now_ns - other_arrival_ns_ <= units::secondsToNanoseconds(config_.hold_s);
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

  tell(pen, contact, force, up, now_ns);
  publish(up);
  return force;
}

// Tell the other station. The leader streams only once the follower has sent an authentic
// PEER of this session, so a replayed HELLO never starts a stream.
void MentorCoupling::Impl::tell(const PenState& pen, const ContactForces& contact, const Vec3& force, bool up,
                                std::int64_t now_ns) noexcept {
  if (!session_->live() || (config_.role == MentorRole::kLeader && !session_->confirmed())) return;
  wire::PeerPayload out;
  out.t_s = pen.t_s;
  out.p_WT = pen.p_WT;
  out.v_WT = pen.v_WT;
  out.f_user_W = contact.f_on_paper_W;
  out.f_coupling_W = force;
  out.energy_in_J = energy_in_J_;
  out.energy_out_J = energy_out_J_;
  out.echo_sender_time_ns = have_other_ ? other_sender_ns_ : 0;
  out.hold_ns = have_other_ ? std::clamp<std::int64_t>(now_ns - other_arrival_ns_, 0, wire::kMaxHoldNs) : 0;
  out.coupling = static_cast<std::uint32_t>(activeCoupling());
  out.flags = (contact.in_contact ? wire::kPeerPenDown : 0u) | (up ? wire::kPeerLinkUp : 0u);
  if (!worthSending(out, now_ns)) {
    bump(peers_withheld_);
    return;
  }
  (void)session_->send(out, now_ns);
  bump(peers_sent_);
  last_sent_ = out;
  last_sent_ns_ = now_ns;
  have_sent_ = true;
}

// For other threads.
void MentorCoupling::Impl::publish(bool up) noexcept {
  if (have_other_) {
    peer_view_.write(PeerView{.valid = true, .t_s = other_state_.t_s, .p_WT = other_state_.p_WT, .v_WT = other_state_.v_WT,
                              .f_user_W = other_state_.f_user_W,
                              .pen_down = (other_state_.flags & wire::kPeerPenDown) != 0});
  }
  link_flag_.store(up, std::memory_order_relaxed);
  energy_in_snapshot_.store(energy_in_J_, std::memory_order_relaxed);
  energy_out_snapshot_.store(energy_out_J_, std::memory_order_relaxed);
  peer_energy_snapshot_.store(other_state_.energy_in_J, std::memory_order_relaxed);
  dissipated_snapshot_.store(dissipated_J_, std::memory_order_relaxed);
}

MentorCoupling::MentorCoupling(const MentorConfig& config, wire::DatagramLink& link)
    : impl_(std::make_unique<Impl>(config, link)) {}

MentorCoupling::~MentorCoupling() = default;

Vec3 MentorCoupling::compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept {
  return impl_->compute(pen, contact, dt_s);
}

void MentorCoupling::close(std::int64_t now_ns) noexcept { impl_->session_->close(now_ns); }

TripleBuffer<PeerView>& MentorCoupling::peer() noexcept { return impl_->peer_view_; }

const MentorConfig& MentorCoupling::config() const noexcept { return impl_->config_; }

// The perceptual deadband: a change the other person could feel or see, a change of state,
// or the heartbeat that keeps the link up.
bool MentorCoupling::Impl::worthSending(const wire::PeerPayload& out, std::int64_t now_ns) const noexcept {
  if (config_.deadband <= 0.0 || !have_sent_) return true;
  if (now_ns - last_sent_ns_ >= units::secondsToNanoseconds(config_.heartbeat_s)) return true;
  if (out.flags != last_sent_.flags || out.coupling != last_sent_.coupling) return true;
  const auto beyondWeber = [k = config_.deadband](const Vec3& now, const Vec3& sent) {
    return (now - sent).norm() > k * sent.norm();
  };
  return beyondWeber(out.v_WT, last_sent_.v_WT) || beyondWeber(out.f_user_W, last_sent_.f_user_W) ||
         beyondWeber(out.f_coupling_W, last_sent_.f_coupling_W) ||
         (out.p_WT - last_sent_.p_WT).norm() > config_.deadband_position_m;
}

MentorStats MentorCoupling::stats() const noexcept {
  const Impl& i = *impl_;
  const wire::LinkSessionStats session = i.session_->stats();
  MentorStats s;
  s.session = i.session_->live();
  s.link_up = i.link_flag_.load(std::memory_order_relaxed);
  s.sessions = session.sessions;
  s.busy_refusals = i.config_.role == MentorRole::kLeader ? session.busy : 0;
  s.refused_busy = i.refused_.load();
  s.link_faults = i.link_faults_.load();
  s.goodbyes_received = session.byes_received;
  s.peers_received = session.data_received;
  s.peers_sent = i.peers_sent_.load();
  s.peers_withheld = i.peers_withheld_.load();
  s.lost = session.data_lost;
  s.drops = session.drops;
  s.energy_in_J = i.energy_in_snapshot_.load();
  s.energy_out_J = i.energy_out_snapshot_.load();
  s.peer_energy_in_J = i.peer_energy_snapshot_.load();
  s.dissipated_J = i.dissipated_snapshot_.load();
  s.rtt_s = i.rtt_snapshot_.load();
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
  d.lost -= before.lost;
  d.drops = wire::dropsSince(now.drops, before.drops);
  d.energy_in_J -= before.energy_in_J;
  d.energy_out_J -= before.energy_out_J;
  d.dissipated_J -= before.dissipated_J;
  return d;
}

}  // namespace hattr::net
