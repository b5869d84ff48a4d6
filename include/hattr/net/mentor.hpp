#pragma once
/// Live mentoring ("sympathetic haptics", the paper's section 4.4): an expert's station (the
/// leader) and a trainee's (the follower) share their pens over the network, each running its
/// own servo loop, paper and safety path; a coupling stage on each side turns the other's pen
/// into a force. Same packets, keys and link-fault handling as the network device
/// (docs/protocol.md: HELLO/WELCOME/BUSY/BYE, then PEER packets both ways). docs/mentoring.md
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
#include <limits>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "hattr/core/pen_state.hpp"
#include "hattr/core/triple_buffer.hpp"
#include "hattr/device/net_protocol.hpp"
#include "hattr/device/udp_socket.hpp"
#include "hattr/net/link_emulator.hpp"

namespace hattr::net {

enum class Coupling : std::uint32_t { kObserve = 0, kPosition = 1, kForce = 2, kBilateral = 3 };
/// "observe", "position", "force", "bilateral".
std::string_view couplingName(Coupling coupling) noexcept;
/// The same names; throws InputError listing them.
Coupling parseCoupling(std::string_view text);

enum class MentorRole { kLeader, kFollower };
std::string_view roleName(MentorRole role) noexcept;

/// One datagram transport for the coupling's tick: a UDP socket, or an emulated link in
/// process. Servo-thread functions: noexcept, no allocation, never block.
class DatagramLink {
 public:
  virtual ~DatagramLink() = default;
  /// The next datagram that has arrived by loop time `now_ns`, copied into `buffer`; its size
  /// (which may exceed the buffer: then it was cut) and sender in `size` and `from`.
  virtual bool receive(std::int64_t now_ns, device::net::PacketBuffer& buffer, std::size_t& size,
                       device::net::UdpEndpoint& from) noexcept = 0;
  /// Sends a datagram to `to` at loop time `now_ns`; false if it could not be sent.
  virtual bool send(std::int64_t now_ns, std::span<const std::uint8_t> datagram,
                    const device::net::UdpEndpoint& to) noexcept = 0;
};

/// A UDP socket as a DatagramLink (real time; the loop time is not used).
class UdpDatagramLink final : public DatagramLink {
 public:
  explicit UdpDatagramLink(device::net::UdpSocket socket) : socket_(std::move(socket)) {}
  bool receive(std::int64_t now_ns, device::net::PacketBuffer& buffer, std::size_t& size,
               device::net::UdpEndpoint& from) noexcept override;
  bool send(std::int64_t now_ns, std::span<const std::uint8_t> datagram, const device::net::UdpEndpoint& to) noexcept override;
  [[nodiscard]] device::net::UdpEndpoint localEndpoint() const { return socket_.localEndpoint(); }

 private:
  device::net::UdpSocket socket_;
};

/// Two emulated one-way links between two in-process ends, timed by the loops' own (e.g.
/// simulated) time. end(0) and end(1) are the two stations' links; each end's datagrams come
/// from a fixed made-up address of the other.
class EmulatedLinkPair {
 public:
  EmulatedLinkPair(const LinkConditions& zero_to_one, const LinkConditions& one_to_zero);
  [[nodiscard]] DatagramLink& end(int index) noexcept { return index == 0 ? end0_ : end1_; }
  /// The address each end's datagrams appear to come from.
  [[nodiscard]] static device::net::UdpEndpoint addressOf(int index) noexcept;
  [[nodiscard]] LinkStats stats(int from_index) const noexcept {
    return from_index == 0 ? zero_to_one_.stats() : one_to_zero_.stats();
  }

 private:
  class End final : public DatagramLink {
   public:
    End(LinkEmulator& in, LinkEmulator& out, int peer_index) : in_(in), out_(out), peer_index_(peer_index) {}
    bool receive(std::int64_t now_ns, device::net::PacketBuffer& buffer, std::size_t& size,
                 device::net::UdpEndpoint& from) noexcept override;
    bool send(std::int64_t now_ns, std::span<const std::uint8_t> datagram, const device::net::UdpEndpoint& to) noexcept override;

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
  device::net::AuthKey key;
  device::net::UdpEndpoint leader;         ///< follower: where the leader listens
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
  /// Throws InputError naming the field for a value out of range.
  void validate() const;
};

/// What a station's coupling did. A snapshot of plain numbers.
struct MentorStats {
  bool session = false;              ///< a session with the other station exists
  bool link_up = false;              ///< and its PEER packets are fresh
  std::uint64_t sessions = 0;
  std::uint64_t busy_refusals = 0;   ///< HELLOs refused: a second follower (leader)
  bool refused_busy = false;         ///< this follower was refused (the leader serves another)
  std::uint64_t link_faults = 0;     ///< times the link went down with a session (not by a goodbye)
  std::uint64_t goodbyes_received = 0;  ///< sessions the other station ended (BYE heard)
  std::uint64_t peers_received = 0;
  std::uint64_t peers_sent = 0;
  std::uint64_t peers_withheld = 0;  ///< PEERs the deadband did not send
  std::uint64_t lost = 0;            ///< PEER sequence gaps
  std::array<std::uint64_t, device::net::kDropReasonCount> drops{};
  double energy_in_J = 0.0;          ///< energy this station's person put into the coupling
  double energy_out_J = 0.0;         ///< energy the coupling gave this station's person
  double peer_energy_in_J = 0.0;     ///< the other station's energy in, as last heard
  double dissipated_J = 0.0;         ///< energy the passivity controller took out
  double rtt_s = 0.0;                ///< the latest round-trip estimate
};

/// What happened between two snapshots of one coupling's stats (`before` taken first): the
/// counters and energies as differences, the state (session, link, rtt, lost of the current
/// session) as `now` has them. A station serving session after session reports each one so.
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

/// The coupling stage of one station (see the file comment).
class MentorCoupling final : public GuidanceController {
 public:
  /// `link` must outlive the coupling. Throws InputError for a bad configuration.
  MentorCoupling(const MentorConfig& config, DatagramLink& link);

  /// Servo thread: link I/O, the coupling force, the passivity controller, the PEER packet.
  Vec3 compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept override;
  /// Says BYE to the other station (call after the loop stopped). Not on the servo thread.
  void close(std::int64_t now_ns) noexcept;

  [[nodiscard]] MentorStats stats() const noexcept;
  /// The other station's pen, for one display reader.
  [[nodiscard]] TripleBuffer<PeerView>& peer() noexcept { return peer_view_; }
  [[nodiscard]] const MentorConfig& config() const noexcept { return config_; }

 private:
  void drain(std::int64_t now_ns) noexcept;
  void handle(const device::net::Packet& packet, const device::net::UdpEndpoint& from, std::int64_t now_ns) noexcept;
  void onHello(const device::net::Nonce& nonce, const device::net::UdpEndpoint& from, std::int64_t now_ns) noexcept;
  void sayHello(std::int64_t now_ns) noexcept;
  void send(const device::net::Payload& payload, const device::net::UdpEndpoint& to, std::int64_t now_ns) noexcept;
  Vec3 couplingForce(const PenState& pen, const ContactForces& contact, double dt_s) noexcept;
  Vec3 passive(const Vec3& force, const Vec3& v_WT, double dt_s) noexcept;
  /// The deadband's test: does `out` differ enough from the last PEER sent to be sent now?
  [[nodiscard]] bool worthSending(const device::net::PeerPayload& out, std::int64_t now_ns) const noexcept;
  /// The follower names the coupling; the leader runs the one its follower announces.
  [[nodiscard]] Coupling activeCoupling() const noexcept {
    return config_.role == MentorRole::kLeader && have_other_ ? static_cast<Coupling>(other_state_.coupling)
                                                             : config_.coupling;
  }

  MentorConfig config_;
  DatagramLink& link_;
  device::net::RandomStream random_;
  device::net::PacketBuffer rx_{};
  device::net::PacketBuffer tx_{};
  device::net::SequenceCheck peer_sequence_;
  device::net::DropCounters drops_;

  // Session (leader: the follower's address; follower: the leader's).
  bool session_ = false;
  std::uint64_t session_id_ = 0;
  device::net::Nonce nonce_{};           // the follower's HELLO nonce / the leader's session nonce
  device::net::UdpEndpoint other_{};
  std::uint64_t send_sequence_ = 0;
  std::int64_t last_hello_ns_ = std::numeric_limits<std::int64_t>::min() / 2;
  bool hello_pending_ = false;           // the follower's nonce of the attempt under way
  std::int64_t last_heard_ns_ = 0;

  // The other station as last heard.
  device::net::PeerPayload other_state_{};
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
  device::net::PeerPayload last_sent_{};
  std::int64_t last_sent_ns_ = 0;
  bool have_sent_ = false;

  // Energy bookkeeping of this port (TDPA).
  double energy_in_J_ = 0.0;
  double energy_out_J_ = 0.0;
  double dissipated_J_ = 0.0;

  TripleBuffer<PeerView> peer_view_;
  std::atomic<bool> session_flag_{false};
  std::atomic<bool> link_flag_{false};
  std::atomic<bool> refused_{false};
  std::atomic<std::uint64_t> sessions_{0};
  std::atomic<std::uint64_t> busy_refusals_{0};
  std::atomic<std::uint64_t> link_faults_{0};
  std::atomic<std::uint64_t> goodbyes_{0};
  std::atomic<std::uint64_t> peers_received_{0};
  std::atomic<std::uint64_t> peers_sent_{0};
  std::atomic<std::uint64_t> peers_withheld_{0};
  std::atomic<double> energy_in_snapshot_{0.0};
  std::atomic<double> energy_out_snapshot_{0.0};
  std::atomic<double> peer_energy_snapshot_{0.0};
  std::atomic<double> dissipated_snapshot_{0.0};
  std::atomic<double> rtt_snapshot_{0.0};
  std::atomic<std::uint64_t> lost_snapshot_{0};
};

}  // namespace hattr::net
