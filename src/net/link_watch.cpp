#include "hattr/net/link_watch.hpp"

#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::net {
namespace {

double secondsBetween(LinkWatch::Clock::time_point from, LinkWatch::Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace

LinkWatch::LinkWatch(const LinkWatchSettings& settings, const MentorConfig& mentor, Clock::time_point now)
    : settings_(settings), hold_s_(mentor.hold_s), session_timeout_s_(mentor.session_timeout_s), waiting_since_(now) {
  HATTR_THROW_UNLESS(std::isfinite(settings.give_up_s) && settings.give_up_s >= 0.01 && settings.give_up_s <= 60.0,
                     "give up after the link is down: expected [0.01, 60] s, got {}", settings.give_up_s);
}

void LinkWatch::restart(Clock::time_point now, const MentorStats& stats_now) {
  phase_ = LinkPhase::kWaiting;
  failure_.clear();
  ended_by_other_ = false;
  waiting_since_ = now;
  down_ = false;
  faults_before_ = stats_now.link_faults;
}

double LinkWatch::linkedFor_s(Clock::time_point now) const noexcept {
  return phase_ == LinkPhase::kLinked ? secondsBetween(linked_at_, now) : 0.0;
}

double LinkWatch::downFor_s(Clock::time_point now) const noexcept {
  return phase_ == LinkPhase::kLinked && down_ ? secondsBetween(down_since_, now) : 0.0;
}

void LinkWatch::end() {
  if (phase_ != LinkPhase::kEnded) finish({}, false);
}

void LinkWatch::finish(std::string failure, bool by_other) {
  phase_ = LinkPhase::kEnded;
  failure_ = std::move(failure);
  ended_by_other_ = by_other;
}

std::string LinkWatch::linkLost() const {
  return fmt::format("link lost: nothing from the other station for {:.0f} ms (its force went to zero after {:.0f} ms)",
                     settings_.give_up_s * 1e3, hold_s_ * 1e3);
}

// Waiting: linked, refused or nobody in time. Linked: a goodbye ends it normally, a link down
// for give_up_s ends it as lost.
bool LinkWatch::observe(const MentorStats& stats, Clock::time_point now) {
  if (phase_ == LinkPhase::kEnded) return false;
  if (phase_ == LinkPhase::kWaiting) {
    if (stats.link_up || stats.link_faults > faults_before_) {
      phase_ = LinkPhase::kLinked;
      linked_at_ = now;
      last_up_at_ = now;
      down_ = false;
      return true;
    }
    if (stats.refused_busy) {
      finish(fmt::format("refused: the leader at {} already mentors another follower", settings_.leader_address), false);
    } else if (settings_.wait_s >= 0.0 && secondsBetween(waiting_since_, now) > settings_.wait_s) {
      finish(fmt::format("no other station within {:g} s (a wrong key looks like this too: its packets are dropped "
                         "unanswered)",
                         settings_.wait_s),
             false);
    }
    return false;
  }
  // No session any more: a goodbye, unless the link had been down long enough for the session
  // to time out, which is a lost link.
  if (!stats.session) {
    if (secondsBetween(last_up_at_, now) < session_timeout_s_ - hold_s_) {
      finish({}, true);
    } else {
      finish(linkLost(), false);
    }
    return false;
  }
  if (stats.link_up) {
    down_ = false;
    last_up_at_ = now;
    return false;
  }
  if (!down_ || stats.link_faults != faults_when_down_) {
    down_ = true;
    down_since_ = now;
    faults_when_down_ = stats.link_faults;
    return false;
  }
  if (secondsBetween(down_since_, now) > settings_.give_up_s) finish(linkLost(), false);
  return false;
}

}  // namespace hattr::net
