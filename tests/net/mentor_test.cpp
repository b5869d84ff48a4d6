// Live mentoring: the couplings, the passivity controller, the two-station simulation under
// delay and loss, and the handshake's refusals.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/core/error.hpp"
#include "hattr/net/mentor_station.hpp"
#include "hattr/wire/link_session.hpp"
#include "net/writing_script.hpp"
#include "support/no_allocation.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::net {
namespace {

/// What the expert writes: a loop and a stroke over 2.4 s, pressing 1.2 N.
HapticProfile expertScript() { return test::figureEightScript(2.4); }

/// The follower's pen: held by a compliant hand, so guidance can move it.
constexpr const char* kTraineePen = "sim://pen?hand_stiffness_N_per_m=80";

MentoredRun mentored(Coupling coupling, double rtt_s, double loss, bool passivity = true, double duration_s = 2.4,
                     double deadband = 0.0) {
  const HapticProfile script = expertScript();
  device::ProfileHandScript expert(script);
  LaggingHand trainee(script);
  MentoredSetup setup{.coupling = coupling, .passivity = passivity, .round_trip_s = rtt_s, .loss = loss,
                      .deadband = deadband, .seed = 11, .duration_s = duration_s, .settle_s = 0.8,
                      .follower_device = kTraineePen};
  return runMentoredSimulation(setup, expert, trainee);
}

// A mentoring station's recording is judged as a trial's is (issue 38): an expert pressing 18 N
// where the pen renders 1.75 N sinks through the paper, and the leader's recording says so; the
// follower's, written with the script's 1.2 N, does not.
TEST(Mentoring, AStationsRecordingSaysWhenThePenWentThroughThePaper) {
  HATTR_STARTS_NO_THREAD();
  const HapticProfile light = expertScript();
  HapticProfile heavy(light.metadata());
  for (Sample s : light.samples()) {
    s.f_user_W *= 15.0;
    heavy.append(s);
  }
  device::ProfileHandScript expert(heavy);
  LaggingHand trainee(light);
  const MentoredRun run = runMentoredSimulation(
      {.coupling = Coupling::kObserve, .seed = 11, .duration_s = 2.4, .settle_s = 0.8, .follower_device = kTraineePen},
      expert, trainee);
  const auto& leader = run.leader.metadata().extra;
  ASSERT_EQ(leader.count("physical_penetration"), 1u);
  EXPECT_NE(leader.at("disturbed").find("mm under the paper"), std::string::npos) << leader.at("disturbed");
  EXPECT_EQ(run.follower.metadata().extra.count("physical_penetration"), 0u);
  EXPECT_EQ(run.follower.metadata().extra.count("disturbed"), 0u);
}

TEST(Mentoring, EveryCouplingIsStableAt100MsAnd5PercentLossAndGuidanceBringsTheTraineeCloser) {
  HATTR_STARTS_NO_THREAD();
  const MentoredRun alone = mentored(Coupling::kObserve, 0.1, 0.05);
  const double unguided = test::trajectoryDtw(alone.leader, alone.follower);
  for (const Coupling c : {Coupling::kObserve, Coupling::kPosition, Coupling::kForce, Coupling::kBilateral}) {
    const MentoredRun run = mentored(c, 0.1, 0.05);
    const double dtw = test::trajectoryDtw(run.leader, run.follower);
    std::printf("%-9s tracking %.2f mm, force %.3f N, energy %+.4f J, dissipated %.4f J, peak %.2f N, DTW %.3f mm "
                "(unguided %.3f mm), link faults %llu\n",
                std::string(couplingName(c)).c_str(), run.tracking_rms_m * 1e3, run.force_rms_N, run.energy_generated_J,
                run.dissipated_J, run.peak_coupling_force_N, dtw * 1e3, unguided * 1e3,
                static_cast<unsigned long long>(run.link_faults));
    EXPECT_EQ(run.faults, 0u) << couplingName(c);
    EXPECT_EQ(run.link_faults, 0u) << couplingName(c);
    EXPECT_GT(run.follower.size(), 2300u);
    // Bounded: the couplings' net work stays within what one pen's coupling could do in a stroke.
    EXPECT_LT(std::abs(run.energy_generated_J), 0.5) << couplingName(c);
    if (c == Coupling::kPosition || c == Coupling::kBilateral) {
      EXPECT_LT(dtw, 0.7 * unguided) << couplingName(c);
    }
    if (c == Coupling::kBilateral) {
      EXPECT_LE(run.energy_generated_J, 1e-9);
    }
    if (c == Coupling::kObserve) {
      EXPECT_EQ(run.peak_coupling_force_N, 0.0);
    }
  }
}

TEST(Mentoring, WithoutThePassivityControllerLooselyHeldPensGoUnstableUnderDelayWithItTheyDoNot) {
  HATTR_STARTS_NO_THREAD();
  // Both people hold their pens loosely (no grip stiffness, little damping): the bilateral
  // spring closes a loop over a 200 ms round trip.
  constexpr const char* kLoose = "sim://pen?hand_stiffness_N_per_m=0&hand_damping_N_s_per_m=0.2";
  const HapticProfile script = expertScript();
  const auto run = [&](bool passivity) {
    device::ProfileHandScript expert(script);
    LaggingHand trainee(script);
    return runMentoredSimulation({.coupling = Coupling::kBilateral, .passivity = passivity, .round_trip_s = 0.2,
                                  .seed = 3, .duration_s = 2.4, .settle_s = 0.8, .leader_device = kLoose,
                                  .follower_device = kLoose},
                                 expert, trainee);
  };
  const MentoredRun off = run(false);
  const MentoredRun on = run(true);
  std::printf("passivity off: energy %+.3f J, tracking %.2f mm; on: energy %+.6f J, tracking %.2f mm, dissipated %.4f J\n",
              off.energy_generated_J, off.tracking_rms_m * 1e3, on.energy_generated_J, on.tracking_rms_m * 1e3,
              on.dissipated_J);
  EXPECT_GT(off.energy_generated_J, 1.0);
  EXPECT_GT(off.tracking_rms_m, 0.005);
  EXPECT_LE(on.energy_generated_J, 1e-9);
  EXPECT_LT(on.tracking_rms_m, 0.002);
  EXPECT_GT(on.dissipated_J, 0.0);
}

TEST(MentoringDeadband, SendsFewerPacketsWhileEveryCouplingStaysStableAndGuidesAsWell) {
  HATTR_STARTS_NO_THREAD();
  // Weber fraction 0.1 at 100 ms round trip and 5 % loss: well under a packet per tick, never
  // under the heartbeat's rate, the link never drops, and the same coupling does what it did.
  for (const Coupling c : {Coupling::kPosition, Coupling::kForce, Coupling::kBilateral}) {
    const MentoredRun every_tick = mentored(c, 0.1, 0.05);
    const MentoredRun deadband = mentored(c, 0.1, 0.05, true, 2.4, 0.1);
    std::printf("%-9s packets/s %.0f -> %.0f, tracking %.2f -> %.2f mm, force %.3f -> %.3f N, energy %+.4f J\n",
                std::string(couplingName(c)).c_str(), every_tick.packets_per_s, deadband.packets_per_s,
                every_tick.tracking_rms_m * 1e3, deadband.tracking_rms_m * 1e3, every_tick.force_rms_N,
                deadband.force_rms_N, deadband.energy_generated_J);
    EXPECT_LT(deadband.packets_per_s, 0.6 * every_tick.packets_per_s) << couplingName(c);
    EXPECT_GE(deadband.packets_per_s, 0.95 / MentorConfig{}.heartbeat_s) << couplingName(c);  // the heartbeat, less the loss
    EXPECT_GT(deadband.follower_stats.peers_withheld, 0u);
    EXPECT_EQ(deadband.link_faults, 0u) << couplingName(c);
    EXPECT_EQ(deadband.faults, 0u) << couplingName(c);
    EXPECT_LT(deadband.tracking_rms_m, every_tick.tracking_rms_m + 0.0005) << couplingName(c);
    EXPECT_LT(deadband.force_rms_N, every_tick.force_rms_N + 0.05) << couplingName(c);
    if (c == Coupling::kBilateral) {
      EXPECT_LE(deadband.energy_generated_J, 1e-9);
    }
  }
}

TEST(MentoringDeadband, RefusesAHeartbeatTheLinkWouldNotSurviveAndABadFraction) {
  MentorConfig config{.role = MentorRole::kLeader, .deadband = 0.1};
  config.heartbeat_s = config.hold_s;
  try {
    config.validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "mentoring: heartbeat_s: expected less than hold_s = 0.01 s (or the link drops between "
                           "PEERs), got 0.01");
  }
  config.heartbeat_s = 0.003;
  config.deadband = 1.5;
  try {
    config.validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "mentoring: deadband (Weber fraction): expected [0, 1], got 1.5");
  }
}

TEST(Mentoring, CouplingNamesRoundTripAndBadOnesAreRefused) {
  for (const Coupling c : {Coupling::kObserve, Coupling::kPosition, Coupling::kForce, Coupling::kBilateral}) {
    EXPECT_EQ(parseCoupling(couplingName(c)), c);
  }
  try {
    (void)parseCoupling("telepathy");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "coupling: expected observe, position, force or bilateral, got \"telepathy\"");
  }
}

// A goodbye is a normal end: the station that hears it ends the session with no lost link,
// while a link that goes silent counts one. Two couplings on an in-process link without loss,
// ticked by hand at 1 kHz, so nothing depends on the host's timing.
TEST(Mentoring, AGoodbyeEndsTheSessionWithoutALinkFaultASilentLinkCountsOne) {
  for (const bool goodbye : {true, false}) {
    EmulatedLinkPair link(LinkConditions{}, LinkConditions{});
    const wire::AuthKey key = wire::randomKey();
    MentorCoupling leader(MentorConfig{.role = MentorRole::kLeader, .key = key}, link.end(0));
    MentorCoupling follower(MentorConfig{.role = MentorRole::kFollower, .key = key, .leader = EmulatedLinkPair::addressOf(0)},
                            link.end(1));
    const ContactForces contact;
    int tick = 0;
    const auto run = [&](int ticks, bool follower_ticks) {
      for (int i = 0; i < ticks; ++i, ++tick) {
        const PenState pen{.t_s = tick * 1e-3};
        (void)leader.compute(pen, contact, 1e-3);
        if (follower_ticks) (void)follower.compute(pen, contact, 1e-3);
      }
    };
    run(300, true);
    ASSERT_TRUE(leader.stats().link_up);
    ASSERT_TRUE(follower.stats().link_up);
    if (goodbye) follower.close(static_cast<std::int64_t>(tick) * 1'000'000);
    run(100, false);  // the follower's loop has stopped
    EXPECT_FALSE(leader.stats().link_up);
    EXPECT_EQ(leader.stats().link_faults, goodbye ? 0u : 1u) << (goodbye ? "goodbye" : "silence");
    EXPECT_EQ(leader.stats().goodbyes_received, goodbye ? 1u : 0u);
    EXPECT_EQ(leader.stats().sessions, 1u);
  }
}

TEST(Mentoring, TheLeadersWelcomeTellsItsServoRate) {
  EmulatedLinkPair link(LinkConditions{}, LinkConditions{});
  const wire::AuthKey key = wire::randomKey();
  MentorCoupling leader(MentorConfig{.role = MentorRole::kLeader, .key = key, .rate_hz = 2000.0}, link.end(0));
  // The follower's end of the wire, as a udp:// client or `mentor follow` says HELLO.
  wire::InitiatorLinkSession follower(key, wire::PacketType::kPeer, link.end(1), EmulatedLinkPair::addressOf(0),
                                      wire::LinkSessionTiming{});
  const ContactForces contact;
  follower.connect(0);
  for (int tick = 0; tick < 200 && follower.state() != wire::InitiatorLinkSession::State::kLive; ++tick) {
    (void)leader.compute(PenState{.t_s = tick * 5e-4}, contact, 5e-4);
    follower.pump(static_cast<std::int64_t>(tick) * 500'000);
  }
  ASSERT_EQ(follower.state(), wire::InitiatorLinkSession::State::kLive);
  EXPECT_EQ(follower.welcome().rate_hz, 2000.0);
  EXPECT_THROW((void)MentorCoupling(MentorConfig{.role = MentorRole::kLeader, .key = key, .rate_hz = 0.5}, link.end(0)),
               InputError);
}

// Both stations' ticks (the wire session's handshake and checks, the coupling, the PEERs) never
// allocate nor lock, also while a session opens, a stranger's garbage arrives and a BYE ends it.
TEST(Mentoring, BothStationsTicksNeverAllocateNorLock) {
  EmulatedLinkPair link(LinkConditions{}, LinkConditions{});
  const wire::AuthKey key = wire::randomKey();
  MentorCoupling leader(MentorConfig{.role = MentorRole::kLeader, .coupling = Coupling::kBilateral, .key = key},
                        link.end(0));
  MentorCoupling follower(MentorConfig{.role = MentorRole::kFollower, .coupling = Coupling::kBilateral, .key = key,
                                       .leader = EmulatedLinkPair::addressOf(0)},
                          link.end(1));
  const ContactForces contact{.f_on_paper_W = Vec3(0.0, 0.0, -1.0), .in_contact = true};
  const std::vector<std::uint8_t> garbage(100, 7);
  const auto tick = [&](int i) {
    const PenState pen{.t_s = i * 1e-3, .p_WT = Vec3(1e-4 * (i % 50), 0.0, 0.0)};
    (void)leader.compute(pen, contact, 1e-3);
    (void)follower.compute(pen, contact, 1e-3);
  };
  tick(0);  // warm up outside the scope
  const test::NoAllocationScope scope;
  for (int i = 1; i < 2000; ++i) {
    if (i % 100 == 0) (void)link.end(1).send(i * 1'000'000, garbage, EmulatedLinkPair::addressOf(0));
    tick(i);
  }
  follower.close(2000 * 1'000'000);
  tick(2000);
  EXPECT_EQ(scope.allocations(), 0u);
  if (test::lockHookActive()) {
    EXPECT_EQ(scope.locks(), 0u);
  }
  EXPECT_EQ(leader.stats().sessions, 1u);
  EXPECT_GT(leader.stats().peers_received, 1900u);
  EXPECT_GE(leader.stats().drops[static_cast<std::size_t>(wire::DropReason::kBadHeader)], 19u);
  EXPECT_EQ(leader.stats().goodbyes_received, 1u);
}

/// A station's link that, when asked, hands the station its own last datagram back as if the
/// other station had sent it: a relay without the key reflecting one packet.
class ReflectingLink final : public wire::DatagramLink {
 public:
  ReflectingLink(wire::DatagramLink& inner, int other_index) : inner_(inner), other_index_(other_index) {}
  bool receive(std::int64_t now_ns, wire::PacketBuffer& buffer, wire::Received& out) noexcept override {
    if (!reflect_ || last_sent_.empty()) return inner_.receive(now_ns, buffer, out);
    reflect_ = false;
    std::copy(last_sent_.begin(), last_sent_.end(), buffer.begin());
    out.size = last_sent_.size();
    out.from = EmulatedLinkPair::addressOf(other_index_);
    out.arrival_ns = now_ns;
    return true;
  }
  bool send(std::int64_t now_ns, std::span<const std::uint8_t> datagram, const wire::UdpEndpoint& to) noexcept override {
    last_sent_.assign(datagram.begin(), datagram.end());  // test only: allocates
    return inner_.send(now_ns, datagram, to);
  }
  void reflectOnce() { reflect_ = true; }

 private:
  wire::DatagramLink& inner_;
  int other_index_;
  std::vector<std::uint8_t> last_sent_;
  bool reflect_ = false;
};

// Issue 40, item 2: a station's own PEER reflected back to it once, by a relay without the key,
// used to be taken as the other station's pen and end the session ("link lost"). Now it fails
// the MAC of the other direction's key; neither station's link goes down. Both directions.
TEST(Mentoring, AStationsOwnPeerReflectedBackToItIsDroppedAndTheLinkStaysUp) {
  for (const int reflected : {0, 1}) {  // the leader's own packet, then the follower's
    EmulatedLinkPair link(LinkConditions{}, LinkConditions{});
    ReflectingLink leader_link(link.end(0), 1);
    ReflectingLink follower_link(link.end(1), 0);
    const wire::AuthKey key = wire::randomKey();
    MentorCoupling leader(MentorConfig{.role = MentorRole::kLeader, .coupling = Coupling::kPosition, .key = key},
                          leader_link);
    MentorCoupling follower(MentorConfig{.role = MentorRole::kFollower, .coupling = Coupling::kPosition, .key = key,
                                         .leader = EmulatedLinkPair::addressOf(0)},
                            follower_link);
    const ContactForces contact;
    int tick = 0;
    const auto run = [&](int ticks) {
      for (int i = 0; i < ticks; ++i, ++tick) {
        const PenState pen{.t_s = tick * 1e-3, .p_WT = Vec3(0.001 * reflected, 0.0, 0.0)};
        (void)leader.compute(pen, contact, 1e-3);
        (void)follower.compute(pen, contact, 1e-3);
      }
    };
    run(300);
    ASSERT_TRUE(leader.stats().link_up && follower.stats().link_up);
    (reflected == 0 ? leader_link : follower_link).reflectOnce();
    run(500);
    const MentorStats victim = reflected == 0 ? leader.stats() : follower.stats();
    EXPECT_EQ(victim.drops[static_cast<std::size_t>(wire::DropReason::kBadMac)], 1u) << "station " << reflected;
    EXPECT_EQ(victim.drops[static_cast<std::size_t>(wire::DropReason::kOutOfOrder)], 0u) << "station " << reflected;
    EXPECT_EQ(leader.stats().link_faults + follower.stats().link_faults, 0u) << "station " << reflected;
    EXPECT_TRUE(leader.stats().link_up && follower.stats().link_up) << "station " << reflected;
    EXPECT_EQ(leader.stats().sessions, 1u);
  }
}

}  // namespace
}  // namespace hattr::net
