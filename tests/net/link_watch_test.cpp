// The link watch every mentoring front end uses (issue 41): how a session goes, from the
// coupling's statistics, on a clock the test sets.

#include "hattr/net/link_watch.hpp"

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"

namespace hattr::net {
namespace {

using Clock = LinkWatch::Clock;

Clock::time_point at(double seconds) {
  return Clock::time_point(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds)));
}

MentorStats linked(bool up, std::uint64_t faults = 0) { return {.session = true, .link_up = up, .link_faults = faults}; }

const MentorConfig kMentor{};  // hold 10 ms, session timeout 0.5 s

TEST(LinkWatch, NobodyWithinTheWaitOrARefusalEndsTheWait) {
  LinkWatch alone({.wait_s = 1.0}, kMentor, at(0.0));
  EXPECT_FALSE(alone.observe({}, at(0.9)));
  EXPECT_EQ(alone.phase(), LinkPhase::kWaiting);
  EXPECT_FALSE(alone.observe({}, at(1.1)));
  EXPECT_EQ(alone.phase(), LinkPhase::kEnded);
  EXPECT_EQ(alone.failure().rfind("no other station within 1 s (a wrong key looks like this too", 0), 0u) << alone.failure();

  LinkWatch refused({.leader_address = "10.0.0.2:7400"}, kMentor, at(0.0));
  (void)refused.observe({.refused_busy = true}, at(0.1));
  EXPECT_EQ(refused.failure(), "refused: the leader at 10.0.0.2:7400 already mentors another follower");

  LinkWatch serving({.wait_s = -1.0}, kMentor, at(0.0));
  (void)serving.observe({}, at(3600.0));
  EXPECT_EQ(serving.phase(), LinkPhase::kWaiting) << "a lead serving sessions waits without limit";
}

TEST(LinkWatch, ALinkDownLongerThanTheGiveUpTimeIsLostAndOneThatCameBackStartsAgain) {
  LinkWatch watch({.give_up_s = 0.25}, kMentor, at(0.0));
  EXPECT_TRUE(watch.observe(linked(true), at(0.1)));
  EXPECT_FALSE(watch.observe(linked(true), at(0.2))) << "linked is said once";
  (void)watch.observe(linked(false, 1), at(0.3));
  EXPECT_TRUE(watch.linkDown());
  (void)watch.observe(linked(false, 1), at(0.5));
  EXPECT_NEAR(watch.downFor_s(at(0.5)), 0.2, 1e-9);
  (void)watch.observe(linked(true, 1), at(0.52));  // back
  (void)watch.observe(linked(false, 2), at(0.6));  // down again: the count starts again
  (void)watch.observe(linked(false, 2), at(0.8));
  EXPECT_EQ(watch.phase(), LinkPhase::kLinked);
  (void)watch.observe(linked(false, 2), at(0.86));
  EXPECT_EQ(watch.phase(), LinkPhase::kEnded);
  EXPECT_EQ(watch.failure(), "link lost: nothing from the other station for 250 ms (its force went to zero after 10 ms)");
  EXPECT_FALSE(watch.endedByOther());
}

TEST(LinkWatch, AGoodbyeIsANormalEndButASessionThatTimedOutIsALostLink) {
  LinkWatch goodbye({}, kMentor, at(0.0));
  (void)goodbye.observe(linked(true), at(0.1));
  (void)goodbye.observe({.session = false}, at(0.2));
  EXPECT_EQ(goodbye.phase(), LinkPhase::kEnded);
  EXPECT_TRUE(goodbye.failure().empty());
  EXPECT_TRUE(goodbye.endedByOther());

  // Silent since 0.1 s and polled only at 0.7 s: the session ended by its timeout.
  LinkWatch silence({.give_up_s = 5.0}, kMentor, at(0.0));
  (void)silence.observe(linked(true), at(0.1));
  (void)silence.observe({.session = false}, at(0.7));
  EXPECT_FALSE(silence.endedByOther());
  EXPECT_EQ(silence.failure().rfind("link lost:", 0), 0u) << silence.failure();
}

TEST(LinkWatch, TheNextSessionWaitsAgainAndLinkFaultsOfTheLastDoNotCountAsLinked) {
  LinkWatch watch({.wait_s = -1.0}, kMentor, at(0.0));
  (void)watch.observe(linked(true), at(0.1));
  (void)watch.observe(linked(false, 1), at(0.2));
  watch.end();
  EXPECT_EQ(watch.phase(), LinkPhase::kEnded);
  EXPECT_TRUE(watch.failure().empty());
  watch.restart(at(1.0), {.link_faults = 1});
  EXPECT_EQ(watch.phase(), LinkPhase::kWaiting);
  EXPECT_FALSE(watch.observe({.link_faults = 1}, at(1.1)));
  EXPECT_EQ(watch.phase(), LinkPhase::kWaiting);
  // Up and down again between two looks: one more fault means it was linked.
  EXPECT_TRUE(watch.observe({.session = true, .link_faults = 2}, at(1.2)));
}

TEST(LinkWatch, AGiveUpTimeOutOfRangeIsRefused) {
  EXPECT_THROW(LinkWatch({.give_up_s = 0.001}, kMentor, at(0.0)), InputError);
}

}  // namespace
}  // namespace hattr::net
