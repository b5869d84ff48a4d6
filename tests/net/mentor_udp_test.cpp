// Live mentoring over real UDP sockets on loopback, through the link emulator at a 100 ms round
// trip and 5 % loss, in real time: every coupling, a station killed mid-session, and the
// refusals (a second follower, a wrong key, garbage).

#include <cmath>
#include <optional>
#include <thread>

#include <gtest/gtest.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/net/mentor_station.hpp"
#include "net/writing_script.hpp"
#include "support/host_stalls.hpp"

namespace hattr::net {
namespace {

using namespace std::chrono_literals;

HapticProfile udpExpertScript() { return test::figureEightScript(2.0); }


/// A live station on its own real-time loop, its simulated hand released once linked.
struct LiveStation {
  LiveStation(MentorRole role, Coupling coupling, const wire::AuthKey& key, wire::UdpEndpoint leader,
              device::HandScript& script, const std::string& device_uri)
      : link(role == MentorRole::kLeader ? wire::UdpSocket::bound({.address = 0x7F000001u, .port = 0})
                                         : wire::UdpSocket::connected(leader),
             wire::UdpDatagramLink::Clock::kLoop),
        hand(script) {
    StationConfig config{.device_uri = device_uri};
    config.mentor = MentorConfig{.role = role, .coupling = coupling, .key = key, .leader = leader};
    station = std::make_unique<MentorStation>(config, link, &hand);
    station->loop().requireConsumer(&station->recorder().consumerTime());
    station->recorder().startThread();
    station->loop().start();
  }
  ~LiveStation() { stop(); }
  double loopTime() {
    Sample s;
    (void)station->loop().latest().read(s);
    return s.t_s;
  }
  void begin() {
    hand.release(loopTime() + 0.3);
    station->recorder().start();
  }
  HapticProfile stop() {
    if (stopped) return {};
    stopped = true;
    station->loop().stop();
    station->recorder().stopThread();
    return station->takeRecording();
  }
  wire::UdpDatagramLink link;
  HeldHand hand;
  std::unique_ptr<MentorStation> station;
  bool stopped = false;
};

bool waitFor(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

double trajectoryDtwOverLonger(const HapticProfile& a, const HapticProfile& b) {
  double sum = 0.0;
  for (const char* axis : {"x", "y"}) sum += analysis::dtwDistance(a.channel(axis), b.channel(axis));
  return sum / static_cast<double>(std::max(a.size(), b.size()));
}

struct Session {
  HapticProfile leader, follower;
  MentorStats leader_stats, follower_stats;
  std::uint64_t faults = 0;
  std::uint64_t stalls = 0;  ///< both loops' stalls (this host's scheduling)
};

/// One live session of `coupling` through a relay of 50 ms each way and 5 % loss.
Session liveSession(Coupling coupling) {
  const HapticProfile script = udpExpertScript();
  device::ProfileHandScript expert_plan(script);
  LaggingHand trainee_plan(script);
  const wire::AuthKey key = wire::randomKey();
  LiveStation leader(MentorRole::kLeader, coupling, key, {}, expert_plan, "sim://pen");
  const LinkConditions one_way{.delay_s = 0.05, .loss = 0.05, .seed = 9};
  LinkRelay relay("127.0.0.1:0", leader.link.localEndpoint().text(), one_way, {.delay_s = 0.05, .loss = 0.05, .seed = 10});
  LiveStation follower(MentorRole::kFollower, coupling, key, relay.endpoint(), trainee_plan,
                       "sim://pen?hand_stiffness_N_per_m=80");
  EXPECT_TRUE(waitFor([&] { return follower.station->coupling().stats().link_up && leader.station->coupling().stats().link_up; },
                      3000ms));
  leader.begin();
  follower.begin();
  std::this_thread::sleep_for(2600ms);
  Session s;
  s.follower = follower.stop();
  s.leader = leader.stop();
  s.leader_stats = leader.station->coupling().stats();
  s.follower_stats = follower.station->coupling().stats();
  s.faults = leader.station->loop().counters().faults.load() + follower.station->loop().counters().faults.load();
  s.stalls = leader.station->loop().counters().stalls.load() + follower.station->loop().counters().stalls.load();
  return s;
}

TEST(MentoringOverUdp, EveryCouplingIsStableAt100MsAnd5PercentLossAndGuidanceHelps) {
  const Session alone = liveSession(Coupling::kObserve);
  const double unguided = trajectoryDtwOverLonger(alone.leader, alone.follower);
  for (const Coupling c : {Coupling::kPosition, Coupling::kForce, Coupling::kBilateral}) {
    (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
      const Session s = liveSession(c);
      stalls = s.stalls;
      const double dtw = trajectoryDtwOverLonger(s.leader, s.follower);
      const double energy = (s.leader_stats.energy_out_J - s.leader_stats.energy_in_J) +
                            (s.follower_stats.energy_out_J - s.follower_stats.energy_in_J);
      std::printf("%-9s DTW %.3f mm (observe %.3f mm), energy %+.4f J, rtt %.0f ms, lost %llu, link faults %llu, "
                  "stalls %llu\n",
                  std::string(couplingName(c)).c_str(), dtw * 1e3, unguided * 1e3, energy, s.follower_stats.rtt_s * 1e3,
                  static_cast<unsigned long long>(s.follower_stats.lost),
                  static_cast<unsigned long long>(s.follower_stats.link_faults + s.leader_stats.link_faults),
                  static_cast<unsigned long long>(s.stalls));
      EXPECT_EQ(s.faults, 0u) << couplingName(c);
      EXPECT_GT(s.follower.duration_s(), 2.0);
      EXPECT_NEAR(s.follower_stats.rtt_s, 0.1, 0.03) << couplingName(c);
      EXPECT_GT(s.follower_stats.lost, 0u);  // the emulator's loss was seen
      EXPECT_LT(std::abs(energy), 0.5) << couplingName(c);
      if (c != Coupling::kForce) {
        EXPECT_LT(dtw, 0.7 * unguided) << couplingName(c);
      }
      if (c == Coupling::kBilateral) {
        EXPECT_LE(energy, 1e-9);
      }
    });
  }
}

TEST(MentoringOverUdp, KillingEitherStationZeroesTheOthersForceWithin20Ms) {
  for (const bool kill_leader : {true, false}) {
    (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
      const HapticProfile script = udpExpertScript();
      device::ProfileHandScript plan_a(script), plan_b(script);
      const wire::AuthKey key = wire::randomKey();
      auto leader = std::make_unique<LiveStation>(MentorRole::kLeader, Coupling::kBilateral, key,
                                                  wire::UdpEndpoint{}, plan_a, "sim://pen");
      auto follower = std::make_unique<LiveStation>(MentorRole::kFollower, Coupling::kBilateral, key,
                                                    leader->link.localEndpoint(), plan_b, "sim://pen");
      ASSERT_TRUE(waitFor([&] { return follower->station->coupling().stats().link_up && leader->station->coupling().stats().link_up; },
                          3000ms));
      leader->begin();
      follower->begin();
      std::this_thread::sleep_for(600ms);
      // The killed station stops dead: no BYE, its loop gone.
      LiveStation& survivor = kill_leader ? *follower : *leader;
      LiveStation& victim = kill_leader ? *leader : *follower;
      victim.station->loop().stop();
      const auto killed = std::chrono::steady_clock::now();
      const bool went_down = waitFor([&] { return !survivor.station->coupling().stats().link_up; }, 1000ms);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - killed).count();
      const auto count_stalls = [&] {
        stalls = victim.station->loop().counters().stalls.load() + survivor.station->loop().counters().stalls.load();
      };
      count_stalls();
      ASSERT_TRUE(went_down);
      std::printf("%s killed: the other's link down after %.1f ms\n", kill_leader ? "leader" : "follower", ms);
      EXPECT_LT(ms, 20.0);
      std::this_thread::sleep_for(5ms);
      Sample last;
      (void)survivor.station->loop().latest().read(last);
      EXPECT_EQ(last.f_guide_W.norm(), 0.0);
      EXPECT_GE(survivor.station->coupling().stats().link_faults, 1u);
      // Nothing recorded is lost: the survivor's recording is whole, every tick's sample in it.
      const HapticProfile kept = survivor.stop();
      count_stalls();
      EXPECT_GT(kept.duration_s(), 0.3);
      EXPECT_EQ(kept.metadata().extra.at("missed_samples"), "0");
    });
  }
}

TEST(MentoringOverUdp, ASecondFollowerAWrongKeyAndGarbageAreRefusedAndCounted) {
  const HapticProfile script = udpExpertScript();
  device::ProfileHandScript a(script), b(script), c(script);
  const wire::AuthKey key = wire::randomKey();
  LiveStation leader(MentorRole::kLeader, Coupling::kObserve, key, {}, a, "sim://pen");
  LiveStation first(MentorRole::kFollower, Coupling::kObserve, key, leader.link.localEndpoint(), b, "sim://pen");
  ASSERT_TRUE(waitFor([&] { return first.station->coupling().stats().link_up; }, 3000ms));
  LiveStation second(MentorRole::kFollower, Coupling::kObserve, key, leader.link.localEndpoint(), c, "sim://pen");
  ASSERT_TRUE(waitFor([&] { return second.station->coupling().stats().refused_busy; }, 3000ms));
  EXPECT_GE(leader.station->coupling().stats().busy_refusals, 1u);
  // A stranger with another key, and garbage, change nothing and are counted.
  auto stranger = wire::UdpSocket::connected(leader.link.localEndpoint());
  wire::PacketBuffer buffer{};
  const wire::Packet hello{{.sender_time_ns = 1}, wire::HelloPayload{}};
  (void)stranger.send(std::span(buffer.data(), wire::encodePacket(hello, wire::randomKey(), buffer)));
  const std::uint8_t garbage[17] = {1, 2, 3};
  (void)stranger.send(garbage);
  ASSERT_TRUE(waitFor([&] {
    const auto d = leader.station->coupling().stats().drops;
    return d[static_cast<std::size_t>(wire::DropReason::kBadMac)] >= 1 &&
           d[static_cast<std::size_t>(wire::DropReason::kBadSize)] >= 1;
  }, 1000ms));
  EXPECT_TRUE(first.station->coupling().stats().link_up);
  EXPECT_EQ(leader.station->coupling().stats().sessions, 1u);
}

}  // namespace
}  // namespace hattr::net
