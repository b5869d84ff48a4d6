#pragma once
/// The studio's live mentoring session (the Mentor tab's logic, without widgets): one
/// net::MentorStation on the studio's device, held by the studio's hand (the mouse or tablet),
/// over a UDP socket, as `hattr mentor lead|follow` runs one (docs/mentoring.md). The leader
/// (the expert) listens, the follower (the trainee) connects and names the coupling; each sees
/// the other's pen live. The session waits for the other station, records this station's side
/// once the two are linked (the pen held lifted, following the hand, while the loop's forces
/// ramp in, as the live rig does), and ends by itself when the other station ends it (its
/// goodbye, a normal end), never answers, refuses (it already mentors someone else) or falls
/// silent for longer than the give-up time (the coupling's force is already zero after its hold
/// time, 10 ms): as `hattr mentor` does. Whatever was recorded is kept; a session that ended by a
/// failure is marked `failed` in the recording's metadata.
///
/// Threads: every member is for the GUI thread (the single reader of the loop's and the
/// coupling's triple buffers); the station's servo thread and recorder thread run meanwhile.
/// SI units inside; addresses and files as the person typed them.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/profile_files.hpp"
#include "core/series.hpp"
#include "hattr/core/haptic_profile.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/net/mentor_station.hpp"
#include "hattr/ops/mentor_station_run.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::studio {

/// Where a leader listens unless told otherwise (docs/mentoring.md's examples).
inline constexpr const char* kDefaultListenAddress = "0.0.0.0:7400";

/// What the person chose in the Mentor tab, and the studio's device (the library's options:
/// the address, key file, coupling, passivity, deadband, device, world, rate, subject, wait and
/// give-up times), and their check, opening nothing (ops::mentorSetupFor).
using MentorSettings = ops::MentorStationOptions;
using ops::MentorSetup;
using ops::mentorSetupFor;

enum class MentorPhase {
  kIdle,     ///< no session yet
  kWaiting,  ///< listening (leader) or saying HELLO (follower) until the link is up
  kLinked,   ///< the link came up: both sides see each other, this side records
  kEnded,    ///< over: stopped by this person, or by a failure (MentorSnapshot::failure)
};

/// The session's state for a display: plain values, copied.
struct MentorSnapshot {
  MentorPhase phase = MentorPhase::kIdle;
  net::MentorRole role = net::MentorRole::kLeader;
  std::string where;        ///< "listening on 0.0.0.0:7400" or "connecting to 10.0.0.2:7400"
  std::string failure;      ///< why a session failed ("link lost: ..."); empty otherwise
  bool ended_by_other = false;     ///< the other station ended the session (its goodbye): a normal end
  net::MentorStats stats;   ///< the coupling's counters (the last ones once the session is over)
  bool link_down_now = false;      ///< linked, but the link is down at the moment
  double link_down_s = 0.0;        ///< how long it has been down [s]
  double linked_s = 0.0;           ///< time since the link first came up [s]
  std::uint64_t ticks = 0;         ///< the station's loop
  std::uint64_t overruns = 0;
  std::uint64_t faults = 0;
  std::uint64_t stalls = 0;
};

/// One line of "what is happening" for the person: "listening on …", "linked", "link lost: …".
std::string mentorPhaseText(const MentorSnapshot& snapshot);

class MentorSession {
 public:
  MentorSession();
  ~MentorSession();
  MentorSession(const MentorSession&) = delete;
  MentorSession& operator=(const MentorSession&) = delete;

  /// Starts a session on `hand` (must outlive it; nothing else may drive it meanwhile): reads
  /// the key, binds the socket, opens the device, starts the servo loop and the recorder's
  /// thread. A session in progress is stopped first; the last session's recording is dropped
  /// once the new one starts (ask the person first). Throws InputError (a bad key file or
  /// address, a bad device) or hattr::Error (the port is taken); then nothing runs and the
  /// last recording stays.
  void start(const MentorSettings& settings, device::HandScript& hand);

  /// At display rate: reads this station's pen and the other's, extends the other's trail and
  /// watches the link. Returns true when the session has just ended by itself (see failure).
  bool poll();

  /// Ends the session (Disconnect): stops the loop, says BYE to the other station and keeps
  /// the recording. No-op when none runs.
  void stop();

  /// A session runs (waiting or linked).
  [[nodiscard]] bool active() const noexcept { return run_ != nullptr; }
  [[nodiscard]] MentorSnapshot snapshot() const;
  /// This station's pen as last read by poll() (nullopt before the first sample).
  [[nodiscard]] const std::optional<Sample>& ownPen() const noexcept { return own_; }
  /// True when poll() read a sample of this station's pen it had not read before.
  [[nodiscard]] bool ownPenFresh() const noexcept { return own_fresh_; }
  /// The other station's pen as last heard (valid = false before any PEER).
  [[nodiscard]] const net::PeerView& peer() const noexcept { return peer_; }
  /// The other station's pen-down strokes, as poll() saw them (at display rate).
  [[nodiscard]] const Trail& peerTrail() const noexcept { return peer_trail_; }
  void clearPeerTrail() { peer_trail_.clear(); }
  /// The gains and world settings clamped to the device (MentorStation::clamps()).
  [[nodiscard]] const std::vector<std::string>& clamps() const noexcept { return clamps_; }
  /// Where the socket is bound (the leader's port when it asked for port 0). Only while active().
  [[nodiscard]] wire::UdpEndpoint localEndpoint() const;
  /// The station's loop counters, while active() (null otherwise).
  [[nodiscard]] const servo::LiveCounters* counters() const noexcept;

  /// The last session's recording (this station's side, metadata `failed` when it failed);
  /// nullopt when nothing was recorded (the link never came up).
  [[nodiscard]] const std::optional<HapticProfile>& recording() const noexcept { return recording_; }
  [[nodiscard]] bool recordingSaved() const noexcept { return recording_saved_; }
  /// Writes the recording with io::writeProfileCsv (atomic); an existing file is replaced
  /// only when `replace_confirmed` (profile_files.hpp). Throws InputError naming the file.
  SaveOutcome saveRecording(const std::filesystem::path& file, bool replace_confirmed);
  /// The recording is dropped (the person agreed to lose it).
  void discardRecording();

 private:
  using Clock = ops::MentorStationRun::Clock;
  void end();
  void copyCounters(MentorSnapshot& out) const;

  MentorSettings settings_;
  // The station, its link watch and recorder hand-over: the one `hattr mentor` uses too.
  std::unique_ptr<ops::MentorStationRun> run_;
  MentorPhase phase_ = MentorPhase::kIdle;
  std::string where_;
  std::string failure_;
  std::vector<std::string> clamps_;
  net::MentorStats last_stats_;
  MentorSnapshot final_counters_;  // the loop's counters when the session ended
  bool ended_by_other_ = false;

  // What the display shows.
  std::optional<Sample> own_;
  bool own_fresh_ = false;
  net::PeerView peer_{};
  Trail peer_trail_{20'000};

  std::optional<HapticProfile> recording_;
  bool recording_saved_ = true;
};

}  // namespace hattr::studio
