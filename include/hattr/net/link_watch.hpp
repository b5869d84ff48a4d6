#pragma once
/// How a live mentoring session goes, judged from the coupling's statistics the same way in
/// every front end (`hattr mentor lead|follow`, the studio's Mentor tab): waiting for the other
/// station (linked; refused because the leader mentors someone else; or nobody within the wait),
/// then linked until the other station says goodbye (a normal end) or the link stays down longer
/// than the give-up time (lost; a link that came back in between starts the count again). A
/// session that ended after the link had been down long enough for it to time out is a lost
/// link, not a goodbye.
///
/// Threads: one thread (the front end's), polling every few ms.

#include <chrono>
#include <string>

#include "hattr/net/mentor.hpp"

namespace hattr::net {

struct LinkWatchSettings {
  double wait_s = 30.0;          ///< how long to wait for the other station; < 0: without limit
  double give_up_s = 0.25;       ///< a linked session whose link stays down this long is lost [s]
  std::string leader_address;    ///< a follower's leader, for the refusal's message
};

enum class LinkPhase { kWaiting, kLinked, kEnded };

class LinkWatch {
 public:
  using Clock = std::chrono::steady_clock;

  /// `mentor`: the station's configuration (its hold and session timeout). Waits from `now`.
  /// Throws InputError for a give-up time outside [0.01, 60] s.
  LinkWatch(const LinkWatchSettings& settings, const MentorConfig& mentor, Clock::time_point now);

  /// Reads the coupling's statistics at `now`. Returns true once, when the link has come up
  /// (the caller releases the hands and starts recording).
  bool observe(const MentorStats& stats, Clock::time_point now);
  /// Waits for the next session (a leader serving one after another) from `now`; `stats_now`:
  /// the coupling's statistics at that moment (its link faults count over all its sessions).
  void restart(Clock::time_point now, const MentorStats& stats_now);
  /// Ends the session here (the caller's stop, its time up): a normal end, unless it had ended.
  void end();

  [[nodiscard]] LinkPhase phase() const noexcept { return phase_; }
  /// Why the session ended: "" for a normal end (a goodbye, or end()).
  [[nodiscard]] const std::string& failure() const noexcept { return failure_; }
  /// The other station ended the session (its goodbye).
  [[nodiscard]] bool endedByOther() const noexcept { return ended_by_other_; }
  /// Linked: how long since the link came up [s] (0 otherwise).
  [[nodiscard]] double linkedFor_s(Clock::time_point now) const noexcept;
  /// Linked, and the link was down at the last observe().
  [[nodiscard]] bool linkDown() const noexcept { return phase_ == LinkPhase::kLinked && down_; }
  /// Linked and the link down: how long it has been down [s] (0 otherwise).
  [[nodiscard]] double downFor_s(Clock::time_point now) const noexcept;

 private:
  void finish(std::string failure, bool by_other);
  [[nodiscard]] std::string linkLost() const;

  LinkWatchSettings settings_;
  double hold_s_;
  double session_timeout_s_;
  LinkPhase phase_ = LinkPhase::kWaiting;
  std::string failure_;
  bool ended_by_other_ = false;
  Clock::time_point waiting_since_;
  Clock::time_point linked_at_{};
  Clock::time_point last_up_at_{};
  bool down_ = false;
  Clock::time_point down_since_{};
  std::uint64_t faults_when_down_ = 0;
  // The coupling's link faults when the wait began (they count over a station's sessions): one
  // more while waiting means the link came up and went down between two looks.
  std::uint64_t faults_before_ = 0;
};

}  // namespace hattr::net
