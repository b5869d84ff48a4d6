#pragma once
/// One live-mentoring station's sessions as one library object (`hattr mentor lead|follow`,
/// the studio's Mentor tab; docs/mentoring.md): the settings checked (key, address), the socket
/// and the device opened, the servo loop and the recorder's thread running; then per session
/// the link watched (net::LinkWatch: linked, refused, nobody in time, a goodbye, a lost link),
/// the recording started once linked and handed over when the session ends (everything the
/// loop published before the end is the session's, marked `failed` on a failure, with the
/// session's own counters); a leader then waits for its next follower. Closing says goodbye.
///
/// Threads: every member is for one thread (the front end's), polling every few ms; the
/// station's servo thread and recorder thread run meanwhile.

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/net/link_watch.hpp"
#include "hattr/net/mentor_station.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/wire/datagram_link.hpp"

namespace hattr::ops {

/// What a person sets up for one station.
struct MentorStationOptions {
  net::MentorRole role = net::MentorRole::kLeader;
  /// Leader: ADDR:PORT to listen on (port 0: any free port). Follower: the leader's HOST:PORT.
  std::string address;
  std::filesystem::path key_file;                    ///< made by `hattr device keygen`
  net::Coupling coupling = net::Coupling::kObserve;  ///< the follower's; a leader runs its follower's
  bool passivity = true;                             ///< the passivity observer/controller (bilateral)
  double deadband = 0.0;                             ///< perceptual deadband, a Weber fraction (0: off)
  std::string device_uri = "sim://pen";
  render::WorldConfig world{};
  double rate_hz = 1000.0;
  std::string subject;       ///< recorded as the subject; "": "expert" (leader) or "trainee"
  double wait_s = 30.0;      ///< how long to wait for the other station [s]; < 0: without limit
  double give_up_s = 0.25;   ///< a linked session whose link stays down this long is lost [s]
  /// How messages name the address and the key: the CLI's flags, the studio's fields.
  std::string listen_what = "listen address";
  std::string connect_what = "leader's address";
  std::string key_what = "key file";
};

/// The coupling's configuration and the leader's socket address, checked.
struct MentorSetup {
  net::MentorConfig mentor;  ///< role, coupling, key, leader's address, passivity, deadband
  wire::UdpEndpoint bind;    ///< where a leader's socket is bound (a follower's is connected to mentor.leader)
};

/// Parses the address and reads the key, opening nothing (the library's messages:
/// wire::parseUdpEndpoint, wire::readKeyFile, MentorConfig::validate). Throws InputError.
MentorSetup mentorSetupFor(const MentorStationOptions& options);

/// What one session did.
struct MentorSessionOutcome {
  HapticProfile recording;     ///< this station's side (metadata `failed` on a failure); empty if never linked
  net::MentorStats stats;      ///< the session's own figures (net::statsSince)
  std::string failure;         ///< "" for a normal end (a goodbye, the time up, stopped)
  bool ended_by_other = false; ///< the other station said goodbye
  /// The session's figures as `hattr mentor --json` prints them: samples, peers_received,
  /// peers_sent, peers_withheld, lost, link_faults, busy_refusals, drops, energy_in_J,
  /// energy_out_J, dissipated_J, rtt_ms, failure (the caller adds the file it wrote).
  [[nodiscard]] nlohmann::json toJson() const;
};

class MentorStationRun {
 public:
  using Clock = net::LinkWatch::Clock;

  /// How the station's hand (null: none) waits for the link.
  enum class HandStart {
    kHeldUntilLinked,  ///< lifted until the link is up, then the script from there (a scripted hand)
    kFromTheStart,     ///< drives the pen from the start (a person's hand, the mouse or a tablet)
  };

  /// Checks the options, binds the socket, opens the device, starts the servo loop and the
  /// recorder's thread, and waits for the first session from now. `hand` must outlive the
  /// run. Throws InputError (a bad key file, address or device) or hattr::Error (the port is
  /// taken); then nothing runs.
  MentorStationRun(const MentorStationOptions& options, device::HandScript* hand, HandStart start);
  ~MentorStationRun();
  MentorStationRun(const MentorStationRun&) = delete;
  MentorStationRun& operator=(const MentorStationRun&) = delete;

  /// "listening on 0.0.0.0:7400" or "connecting to 10.0.0.2:7400".
  [[nodiscard]] const std::string& where() const noexcept { return where_; }
  [[nodiscard]] wire::UdpEndpoint localEndpoint() const { return link_->localEndpoint(); }
  [[nodiscard]] const net::MentorConfig& mentor() const noexcept { return setup_.mentor; }
  [[nodiscard]] net::MentorStation& station() noexcept { return *station_; }
  [[nodiscard]] const net::LinkWatch& watch() const noexcept { return watch_; }
  /// The session is over (poll() saw it end, or endNow()).
  [[nodiscard]] bool ended() const noexcept { return watch_.phase() == net::LinkPhase::kEnded; }
  /// Why the session ended: "" for a normal end; "the servo loop stopped" when the loop did.
  [[nodiscard]] std::string failure() const { return loop_stopped_ ? "the servo loop stopped" : watch_.failure(); }
  /// The station's servo loop has stopped by itself: no next session can run.
  [[nodiscard]] bool loopStopped() const noexcept { return loop_stopped_; }
  /// The loop time of the station's newest sample [s].
  [[nodiscard]] double loopTime();

  /// Reads the coupling at `now`: true once, when the link has come up (recording starts, a
  /// held hand is released after the coupling's fade-in). A stopped loop ends the session.
  bool poll(Clock::time_point now);
  /// Ends the session here (the person's stop, the time up): a normal end, unless it had ended.
  void endNow();
  /// The session is over: hands over its recording (what the loop published before now) and
  /// its figures. The loop runs on, for the next session.
  MentorSessionOutcome takeSession();
  /// Ready for the next follower: the hand lifted and rewound, a fresh recording, the wait from
  /// now. After takeSession(); not once the loop stopped (loopStopped()).
  void nextSession(Clock::time_point now);
  /// Stops the loop and the recorder, says goodbye to the other station. Idempotent.
  void close();

 private:
  MentorSetup setup_;
  std::string where_;
  std::unique_ptr<net::HeldHand> held_;
  std::unique_ptr<device::HandScript> settling_;
  std::unique_ptr<wire::UdpDatagramLink> link_;
  std::unique_ptr<net::MentorStation> station_;
  net::LinkWatch watch_;
  net::MentorStats before_session_{};
  bool loop_stopped_ = false;
  bool closed_ = false;
};

}  // namespace hattr::ops
