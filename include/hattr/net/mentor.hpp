#pragma once
/// Live mentoring ("sympathetic haptics", the paper's section 4.4): an expert's station (the
/// leader) and a trainee's (the follower) share their pens over the network, each running its
/// own servo loop, paper and safety path; a coupling stage on each side turns the other's pen
/// into a force. Same packets, keys, sessions and link-fault handling as the network device
/// (docs/protocol.md: HELLO/COOKIE/WELCOME/BUSY/BYE, then PEER packets both ways). docs/mentoring.md
/// gives the couplings, the passivity method and the measured figures.
///
/// Couplings:
///   observe    no force; each side sees the other's pen;
///   position   the follower is pulled toward the leader's current pen in the paper plane
///              (live PCONTROL: Kp·Δp + Kd·Δv);
///   force      the follower feels the difference between the leader's force on the paper and
///              its own (live ALPHA: Kp·e + Kd·ė, per axis, while its pen touches the paper);
///   bilateral  a virtual spring-damper between the two pens in the paper plane acts on both,
///              so the mentor feels the student resist.
/// For bilateral, the loop closes over the network, and delay makes the coupling generate
/// energy; the time-domain passivity observer and controller of Ryu & Hannaford (2002), in the
/// two-port form with energy exchange of Ryu, Artigas & Preusche (2010), keep it passive: each
/// side gives its person at most the energy the other side's person put in (as last heard).
///
/// Threads: construction is setup code (throws); compute() runs on the servo thread (no
/// allocation, no locks, non-blocking I/O only); stats() and peer() from any thread.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "hattr/core/pen_state.hpp"
#include "hattr/core/guidance_controller.hpp"
#include "hattr/core/triple_buffer.hpp"
#include "hattr/wire/datagram_link.hpp"
#include "hattr/wire/keys.hpp"
#include "hattr/wire/packet.hpp"
#include "hattr/wire/udp_socket.hpp"
#include "hattr/net/link_emulator.hpp"

namespace hattr::net {

enum class Coupling : std::uint32_t { kObserve = 0, kPosition = 1, kForce = 2, kBilateral = 3 };
/// "observe", "position", "force", "bilateral".
std::string_view couplingName(Coupling coupling) noexcept;
/// The same names; throws InputError listing them.
Coupling parseCoupling(std::string_view text);

enum class MentorRole { kLeader, kFollower };
std::string_view roleName(MentorRole role) noexcept;

/// Two emulated one-way links between two in-process ends, timed by the loops' own (e.g.
/// simulated) time. end(0) and end(1) are the two stations' links; each end's datagrams come
/// from a fixed made-up address of the other.
class EmulatedLinkPair {
 public:
  EmulatedLinkPair(const LinkConditions& zero_to_one, const LinkConditions& one_to_zero);
  [[nodiscard]] wire::DatagramLink& end(int index) noexcept { return index == 0 ? end0_ : end1_; }
  /// The address each end's datagrams appear to come from.
  [[nodiscard]] static wire::UdpEndpoint addressOf(int index) noexcept;
  [[nodiscard]] LinkStats stats(int from_index) const noexcept {
    return from_index == 0 ? zero_to_one_.stats() : one_to_zero_.stats();
  }

 private:
  class End final : public wire::DatagramLink {
   public:
    End(LinkEmulator& in, LinkEmulator& out, int peer_index) : in_(in), out_(out), peer_index_(peer_index) {}
    bool receive(std::int64_t now_ns, wire::PacketBuffer& buffer, wire::Received& out) noexcept override;
    bool send(std::int64_t now_ns, std::span<const std::uint8_t> datagram, const wire::UdpEndpoint& to) noexcept override;

   private:
    LinkEmulator& in_;
    LinkEmulator& out_;
    int peer_index_;
  };
  LinkEmulator zero_to_one_;
  LinkEmulator one_to_zero_;
  End end0_;
  End end1_;
};

struct CouplingGains {
  double position_kp_N_per_m = 350.0;    ///< live PCONTROL (the paper's 0.35 N/mm)
  double position_kd_N_s_per_m = 170.0;  ///< the paper's 0.17 N·s/mm (clamped to the device)
  double force_kp = 0.5;                 ///< live ALPHA (the paper's)
  double force_kd_s = 0.1;
  double force_derivative_cutoff_hz = 20.0;
  double bilateral_k_N_per_m = 300.0;    ///< the virtual spring between the pens
  double bilateral_b_N_s_per_m = 2.0;    ///< and its damper
};

struct MentorConfig {
  MentorRole role = MentorRole::kFollower;
  Coupling coupling = Coupling::kObserve;  ///< the follower's choice; the leader runs what its follower announces
  CouplingGains gains;
  bool passivity = true;                   ///< the passivity observer/controller (bilateral)
  wire::AuthKey key;
  wire::UdpEndpoint leader;         ///< follower: where the leader listens
  double hold_s = 0.010;                   ///< no PEER for this long: the link is down, zero force
  double ramp_s = 0.25;                    ///< the coupling fades in over this long when the link is up
  double session_timeout_s = 0.5;          ///< the leader ends a silent session after this
  double hello_interval_s = 0.05;          ///< the follower says HELLO this often until welcomed
  /// Perceptual deadband (Hinterseer & Steinbach): 0 sends a PEER every tick; k > 0 sends one
  /// only when the pen's velocity or force has changed by more than k (a Weber fraction) of
  /// the last one sent, its position by more than deadband_position_m, its flags or coupling
  /// changed, or heartbeat_s has passed. The other station holds the last values.
  double deadband = 0.0;
  double deadband_position_m = 0.0002;     ///< [m]; hand position discrimination is ~1 mm or coarser
  double heartbeat_s = 0.003;              ///< at most this long between PEERs (< hold_s; hold_s / 3 survives two lost in a row)
  double rate_hz = 1000.0;                 ///< the station's servo rate, told in the leader's WELCOME [Hz]
  /// Throws InputError naming the field for a value out of range.
  void validate() const;
};

/// What a station's coupling did. A snapshot of plain numbers.
struct MentorStats {
  bool session = false;              ///< a session with the other station exists
  bool link_up = false;              ///< and its PEER packets are fresh
  std::uint64_t sessions = 0;        ///< sessions opened with the other station
  std::uint64_t busy_refusals = 0;   ///< HELLOs refused: a second follower (leader)
  bool refused_busy = false;         ///< this follower was refused (the leader serves another)
  std::uint64_t link_faults = 0;     ///< times the link went down with a session (not by a goodbye)
  std::uint64_t goodbyes_received = 0;  ///< sessions the other station ended (BYE heard)
  std::uint64_t peers_received = 0;  ///< authentic PEER packets of the live session accepted
  std::uint64_t peers_sent = 0;      ///< PEER packets sent
  std::uint64_t peers_withheld = 0;  ///< PEERs the deadband did not send
  std::uint64_t lost = 0;            ///< PEER sequence gaps (all sessions)
  wire::DropCounts drops{};          ///< datagrams dropped, by wire::DropReason
  double energy_in_J = 0.0;          ///< energy this station's person put into the coupling
  double energy_out_J = 0.0;         ///< energy the coupling gave this station's person
  double peer_energy_in_J = 0.0;     ///< the other station's energy in, as last heard
  double dissipated_J = 0.0;         ///< energy the passivity controller took out
  double rtt_s = 0.0;                ///< the latest round-trip estimate
};

/// What happened between two snapshots of one coupling's stats (`before` taken first): the
/// counters and energies as differences, the state (session, link, rtt) as `now` has them. A station serving session after session reports each one so.
[[nodiscard]] MentorStats statsSince(const MentorStats& now, const MentorStats& before) noexcept;

/// The other station's pen as last heard (for a display).
struct PeerView {
  bool valid = false;
  double t_s = 0.0;
  Vec3 p_WT = Vec3::Zero();
  Vec3 v_WT = Vec3::Zero();
  Vec3 f_user_W = Vec3::Zero();
  bool pen_down = false;
};

/// The coupling stage of one station (see the file comment). The session (handshake, checks,
/// timeouts) is the wire protocol's: the leader a wire::ResponderLinkSession, the follower a
/// wire::InitiatorLinkSession, the same the device server and the udp:// client use.
class MentorCoupling final : public GuidanceController {
 public:
  /// `link` must outlive the coupling. Throws InputError for a bad configuration.
  MentorCoupling(const MentorConfig& config, wire::DatagramLink& link);
  ~MentorCoupling() override;
  MentorCoupling(const MentorCoupling&) = delete;
  MentorCoupling& operator=(const MentorCoupling&) = delete;

  /// Servo thread: link I/O, the coupling force, the passivity controller, the PEER packet.
  Vec3 compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept override;
  /// Says BYE to the other station (call after the loop stopped). Not on the servo thread.
  void close(std::int64_t now_ns) noexcept;

  [[nodiscard]] MentorStats stats() const noexcept;
  /// The other station's pen, for one display reader.
  [[nodiscard]] TripleBuffer<PeerView>& peer() noexcept;
  [[nodiscard]] const MentorConfig& config() const noexcept;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace hattr::net
