// Record and play through the whole pipeline: simulated hands on the simulated pen, the
// paper, the training modes, the servo loop and the recorder.

#include <cmath>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/simulated_device.hpp"
#include "hattr/render/flat_paper.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/servo/servo_loop.hpp"
#include "hattr/session/recorder.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::session {
namespace {

/// What the expert means to write: a smooth curve over 2 s, pressing 1.2 N.
HapticProfile writingScript(double press_scale = 1.0) {
  HapticProfile p;
  for (int i = 0; i <= 200; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    const double a = 3.0 * s.t_s;
    s.p_WT = Vec3(0.02 * std::sin(a), 0.01 * std::sin(2 * a), 0.0);
    s.v_WT = Vec3(0.06 * std::cos(a), 0.06 * std::cos(2 * a), 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.2 * press_scale);
    s.pen_down = true;
    p.append(s);
  }
  return p;
}

/// A hand following a script while drifting away from it at `drift_m_per_s` along y.
class DriftingHand final : public device::HandScript {
 public:
  DriftingHand(const HapticProfile& script, double drift_m_per_s) : base_(script), drift_(drift_m_per_s) {}
  device::HandCommand command(double t_s) noexcept override {
    device::HandCommand c = base_.command(t_s);
    c.p_target_W.y() += drift_ * t_s;
    c.v_target_W.y() += drift_;
    return c;
  }
  void rewind() noexcept override { base_.rewind(); }

 private:
  device::ProfileHandScript base_;
  double drift_;
};

struct Fixture {
  Fixture() : env("sim://pen", flatWorld(), 1000.0) {
    device::ProfileHandScript hand(writingScript());
    TrialSetup setup{.duration_s = 2.0};
    setup.metadata.subject = "expert";
    expert = runTrial(env, setup, hand).profile;
    reference = std::make_shared<guidance::ReferenceTrajectory>(expert, 1000.0);
  }
  static render::WorldConfig flatWorld() {
    render::WorldConfig w;
    w.relief.kind = render::ReliefConfig::Kind::kFlat;  // quick to build; same physics
    return w;
  }
  TrialResult train(guidance::TrainingMode mode, device::HandScript& hand) {
    TrialSetup setup{.reference = reference, .duration_s = 2.0};
    setup.guidance.mode = mode;
    return runTrial(env, setup, hand);
  }
  TrialEnvironment env;
  HapticProfile expert;
  std::shared_ptr<guidance::ReferenceTrajectory> reference;
};

TEST(RecordAndTrain, ExpertRecordingHoldsForcesAndMetadata) {
  Fixture f;
  ASSERT_EQ(f.expert.size(), 2000u);
  EXPECT_EQ(f.expert.metadata().extra.at("mode"), "BASIC");
  EXPECT_EQ(f.expert.metadata().extra.at("missed_samples"), "0");
  EXPECT_EQ(f.expert.metadata().nominal_rate_hz, 1000.0);
  // Writing: in contact, pressing with about the script's normal force (the hand presses
  // with the axial force whose normal share is the recorded 1.2 N).
  const Sample& mid = f.expert[1000];
  EXPECT_TRUE(mid.in_contact);
  EXPECT_NEAR(-mid.f_user_W.z(), 1.2, 0.05);
  EXPECT_EQ(mid.f_guide_W, Vec3::Zero());
}

TEST(RecordAndTrain, PositionControlLowersThePositionErrorOfADriftingHand) {
  Fixture f;
  const HapticProfile script = writingScript();
  DriftingHand basic_hand(script, 0.004), guided_hand(script, 0.004);  // 8 mm off by the end
  const TrialResult basic = f.train(guidance::TrainingMode::kBasic, basic_hand);
  const TrialResult guided = f.train(guidance::TrainingMode::kPositionControl, guided_hand);
  const TrialErrors e_basic = trialErrors(basic.profile, *f.reference);
  const TrialErrors e_guided = trialErrors(guided.profile, *f.reference);
  std::cout << "[ info ] RMS position error: BASIC " << e_basic.position_rms_m * 1e3 << " mm, PCONTROL "
            << e_guided.position_rms_m * 1e3 << " mm\n";
  EXPECT_LT(e_guided.position_rms_m, 0.8 * e_basic.position_rms_m);
  // The guidance force is recorded apart from the user's force, and was used.
  double guide = 0;
  for (const Sample& s : guided.profile.samples()) guide = std::max(guide, s.f_guide_W.norm());
  EXPECT_GT(guide, 0.1);
}

TEST(RecordAndTrain, ForceControlLowersTheForceErrorOfAHandPressingTooLightly) {
  Fixture f;
  const HapticProfile light = writingScript(0.5);
  device::ProfileHandScript basic_hand(light), guided_hand(light);
  const TrialResult basic = f.train(guidance::TrainingMode::kBasic, basic_hand);
  const TrialResult guided = f.train(guidance::TrainingMode::kForceControl, guided_hand);
  const TrialErrors e_basic = trialErrors(basic.profile, *f.reference);
  const TrialErrors e_guided = trialErrors(guided.profile, *f.reference);
  std::cout << "[ info ] RMS force error: BASIC " << e_basic.force_rms_N << " N, ALPHA " << e_guided.force_rms_N << " N\n";
  EXPECT_LT(e_guided.force_rms_N, 0.8 * e_basic.force_rms_N);
}

/// CHANNEL's default law in every sample of a drifting hand's trial: no force within 2 mm of the
/// path (its nearest point within 0.5 s), 350 N/m beyond, in the plane; and the hand drifted out.
void expectChannelLaw(const HapticProfile& trial, const guidance::ReferenceTrajectory& ref) {
  const guidance::GuidanceConfig defaults;
  std::size_t checked = 0, outside = 0;
  for (const Sample& s : trial.samples()) {
    const double index = s.t_s / ref.dt_s();
    if (index < 10 || index > static_cast<double>(ref.size()) - 10) continue;
    double nearest = INFINITY;
    const auto at = static_cast<std::size_t>(index);
    for (std::size_t k = at > 500 ? at - 500 : 0; k <= std::min(ref.size() - 1, at + 500); ++k) {
      nearest = std::min(nearest, (s.p_WT - ref[k].p_WT).head<2>().norm());
    }
    const double expected = std::max(0.0, nearest - defaults.channel.half_width_m) * defaults.channel.kp_N_per_m;
    ASSERT_NEAR(s.f_guide_W.norm(), expected, 1e-6) << "t = " << s.t_s;
    EXPECT_EQ(s.f_guide_W.z(), 0.0);
    outside += expected > 0.0 ? 1 : 0;
    ++checked;
  }
  EXPECT_GT(checked, 1500u);
  EXPECT_GT(outside, 200u) << "the hand drifted out of the channel";
}

// Issue 36's strategies, black-box: in a recorded trial of a drifting hand, every sample's
// guidance force is the strategy's law applied to the recorded pen and the expert's reference.
TEST(RecordAndTrain, EachNewStrategysRecordedGuidanceIsItsLawOfTheRecordedPen) {
  Fixture f;
  const HapticProfile script = writingScript();
  const auto trained = [&](guidance::TrainingMode mode, std::uint64_t seed = 1) {
    DriftingHand hand(script, 0.004);  // 8 mm off by the end
    TrialSetup setup{.reference = f.reference, .duration_s = 2.0};
    setup.guidance.mode = mode;
    setup.guidance.noise.seed = seed;
    return runTrial(f.env, setup, hand);
  };
  const guidance::ReferenceTrajectory& ref = *f.reference;

  // CHANNEL: nothing within 2 mm of the path (the nearest point within 0.5 s), 350 N/m beyond.
  const TrialResult channel = trained(guidance::TrainingMode::kChannel);
  expectChannelLaw(channel.profile, ref);
  EXPECT_EQ(channel.profile.metadata().extra.at("channel.half_width_mm"), "2");

  // ERROR-AUGMENTATION: 100 N/m times the deviation from the expert's point at that moment,
  // counted as 10 mm beyond 10 mm.
  const TrialResult augmented = trained(guidance::TrainingMode::kErrorAugmentation);
  std::size_t saturated = 0;
  for (const Sample& s : augmented.profile.samples()) {
    const double index = s.t_s / ref.dt_s();
    if (index > static_cast<double>(ref.size() - 1)) break;
    Vec3 e = s.p_WT - ref.at(index).p_WT;
    e.z() = 0.0;
    if (e.norm() > 0.01) {
      e *= 0.01 / e.norm();
      ++saturated;
    }
    ASSERT_NEAR((s.f_guide_W - 100.0 * e).norm(), 0.0, 1e-6) << "t = " << s.t_s;
  }
  EXPECT_GT(saturated, 0u) << "pushed away, the hand went beyond the saturation";

  // PLAYBACK: the expert's force at that moment, whatever the pen did.
  const TrialResult played = trained(guidance::TrainingMode::kPlayback);
  for (const Sample& s : played.profile.samples()) {
    const double index = s.t_s / ref.dt_s();
    if (index > static_cast<double>(ref.size() - 1)) break;
    ASSERT_NEAR((s.f_guide_W - ref.at(index).f_W).norm(), 0.0, 1e-6) << "t = " << s.t_s;
  }

  // NOISE: the seed's force, again the same, recorded in the plane with its seed.
  const TrialResult noise_a = trained(guidance::TrainingMode::kNoise, 42), noise_b = trained(guidance::TrainingMode::kNoise, 42);
  ASSERT_EQ(noise_a.profile.size(), noise_b.profile.size());
  double sq = 0.0;
  for (std::size_t i = 0; i < noise_a.profile.size(); ++i) {
    EXPECT_EQ(noise_a.profile[i].f_guide_W, noise_b.profile[i].f_guide_W) << i;
    sq += noise_a.profile[i].f_guide_W.head<2>().squaredNorm();
  }
  EXPECT_GT(std::sqrt(sq / static_cast<double>(noise_a.profile.size())), 0.05);
  EXPECT_EQ(noise_a.profile.metadata().extra.at("noise.seed"), "42");
}

// The scheduled strategies, black-box: in a recorded trial of a drifting hand, every sample's
// guidance force is the trial's law applied to the recorded pen, times the trial's gain; the
// metadata names the law, the gain and the law's clamped gains.
TEST(RecordAndTrain, EachScheduledStrategysRecordedGuidanceIsItsLawAtItsGain) {
  Fixture f;
  const HapticProfile script = writingScript();
  const guidance::ReferenceTrajectory& ref = *f.reference;
  const auto trained = [&](guidance::TrainingMode mode, guidance::ScheduledLaw law) {
    DriftingHand hand(script, 0.004);  // 8 mm off by the end
    TrialSetup setup{.reference = f.reference, .duration_s = 2.0};
    setup.guidance.mode = mode;
    setup.guidance.scheduled = law;
    return runTrial(f.env, setup, hand);
  };
  for (const auto mode : {guidance::TrainingMode::kFading, guidance::TrainingMode::kAssistAsNeeded}) {
    const TrialResult r = trained(mode, {guidance::TrainingMode::kPositionControl, 0.4});
    const auto& extra = r.profile.metadata().extra;
    EXPECT_EQ(extra.at("guidance_law"), "PCONTROL");
    EXPECT_EQ(extra.at("guidance_gain"), "0.4");
    EXPECT_NE(extra.at("clamps").find("PCONTROL Kd"), std::string::npos) << "the law's clamps: " << extra.at("clamps");
    // 0.4 × (Kp·(x_ref − x) + Kd·(v_ref − v)) in the plane, with the clamped gains the trial used.
    const double kp = std::stod(extra.at("pcontrol_kp_N_per_m")), kd = std::stod(extra.at("pcontrol_kd_N_s_per_m"));
    EXPECT_EQ(extra.at("pcontrol.kp_N_per_mm"), "0.35");
    std::size_t checked = 0;
    double largest = 0.0;
    for (const Sample& s : r.profile.samples()) {
      const double index = s.t_s / ref.dt_s();
      if (index > static_cast<double>(ref.size() - 1)) break;
      const guidance::ReferencePoint at = ref.at(index);
      Vec3 expected = 0.4 * (kp * (at.p_WT - s.p_WT) + kd * (at.v_WT - s.v_WT));
      expected.z() = 0.0;
      ASSERT_NEAR((s.f_guide_W - expected).norm(), 0.0, 1e-6) << guidance::modeName(mode) << " t = " << s.t_s;
      largest = std::max(largest, s.f_guide_W.norm());
      ++checked;
    }
    EXPECT_GT(checked, 1500u);
    EXPECT_GT(largest, 0.3) << "the drift was pulled back";
  }
  // PARTIAL-THEN-FULL's partial trial: CHANNEL's law at gain 1.
  const TrialResult partial = trained(guidance::TrainingMode::kPartialThenFull, {guidance::TrainingMode::kChannel, 1.0});
  EXPECT_EQ(partial.profile.metadata().extra.at("guidance_law"), "CHANNEL");
  EXPECT_EQ(partial.profile.metadata().extra.at("channel.half_width_mm"), "2");
  expectChannelLaw(partial.profile, ref);
}

TEST(RecordAndTrain, ClampsAreWrittenIntoTheTrialsMetadata) {
  Fixture f;
  device::ProfileHandScript hand(writingScript());
  const TrialResult r = f.train(guidance::TrainingMode::kPositionControl, hand);
  const std::string& clamps = r.profile.metadata().extra.at("clamps");
  EXPECT_NE(clamps.find("PCONTROL Kd 170 N·s/m -> 0.46 N·s/m"), std::string::npos) << clamps;
  EXPECT_EQ(clamps.find("ALPHA"), std::string::npos) << "only the mode in use is reported";
  EXPECT_EQ(r.profile.metadata().extra.at("pcontrol_kp_N_per_m"), "350");
}

TEST(Recorder, MissesNoSampleAtTenKilohertzInRealTime) {
  device::CircleHand hand(Vec3::Zero(), 0.015, 1.0, 1.0);
  device::SimulatedDevice device(device::SimulatedPenParams{}, &hand);
  render::FlatPaper paper;
  servo::ServoConfig config{.rate_hz = 10'000.0};
  config.realtime.policy = servo::RealtimePolicy::kSkip;
  servo::ServoLoop loop(device, config);
  loop.setWorld(&paper);
  Recorder recorder(loop.samples(), RecorderConfig{.nominal_period_s = 1e-4}, ProfileMetadata{});
  recorder.start();
  recorder.startThread();
  loop.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  loop.stop();
  recorder.stopThread();
  const HapticProfile profile = recorder.takeProfile();
  EXPECT_EQ(loop.counters().dropped_samples.load(), 0u);
  EXPECT_EQ(profile.size(), loop.counters().ticks.load());
  EXPECT_EQ(profile.metadata().extra.at("missed_samples"), "0");
  EXPECT_GT(profile.size(), 1000u);
}

TEST(Recorder, CountsSamplesTheRingLost) {
  SpscRing<TickSample> ring(8);
  Recorder recorder(ring, RecorderConfig{.nominal_period_s = 1e-3}, ProfileMetadata{});
  recorder.start();
  for (int i : {0, 1, 2, 5, 6, 10}) {  // 3, 4, 7, 8, 9 never arrived
    Sample s;
    s.t_s = i * 1e-3;
    ASSERT_TRUE(ring.tryPush(TickSample{static_cast<std::uint64_t>(i), s}));
  }
  recorder.drain();
  EXPECT_EQ(recorder.missed(), 5u);
  EXPECT_EQ(recorder.takeProfile().size(), 6u);
}

// An environment opens nothing: a simulated pen's limits come from its URI; any other device's
// are bound by its first trial's open (TrialRun), and a device that answers with other limits
// later is refused, the environment unchanged (issue 63).
TEST(TrialEnvironment, OpensNothingAndBindsAnotherDevicesLimitsOnce) {
  const TrialEnvironment simulated("sim://pen?continuous_force_N=1.2", render::WorldConfig{});
  ASSERT_TRUE(simulated.limitsBound());
  EXPECT_EQ(simulated.limits().continuous_force_N, 1.2);
  EXPECT_EQ(simulated.handRelief(), nullptr) << "the default paper's grain is flat for the hand's reach";

  TrialEnvironment plugin("plugin:/no/such/hattr-plugin.so", render::WorldConfig{});  // not loaded: not opened
  EXPECT_FALSE(plugin.limitsBound());
  EXPECT_THROW((void)plugin.limits(), InvariantError);
  EXPECT_THROW((void)plugin.paper(), InvariantError);
  DeviceLimits limits;
  limits.continuous_force_N = 1.4;
  plugin.bindLimits(limits);
  ASSERT_TRUE(plugin.limitsBound());
  EXPECT_EQ(plugin.limits().continuous_force_N, 1.4);
  EXPECT_NO_THROW((void)plugin.worldClamps());
  EXPECT_NO_THROW(plugin.bindLimits(limits)) << "the same device again";
  DeviceLimits other = limits;
  other.continuous_force_N = 0.9;
  try {
    plugin.bindLimits(other);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("its limits changed since the last trial (continuous force 1.4 N, now 0.9 N"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(plugin.limits().continuous_force_N, 1.4);
}

TEST(Recorder, AResetRecordingCountsNoTicksFromBeforeItAsMissed) {
  SpscRing<TickSample> ring(8);
  Recorder recorder(ring, RecorderConfig{.nominal_period_s = 1e-3}, ProfileMetadata{});
  const auto push = [&](std::initializer_list<int> ticks) {
    for (int i : ticks) {
      Sample s;
      s.t_s = i * 1e-3;
      ASSERT_TRUE(ring.tryPush(TickSample{static_cast<std::uint64_t>(i), s}));
    }
  };
  recorder.start();
  push({0, 1, 2});
  recorder.drain();
  (void)recorder.takeProfile();
  // The loop ran on between two sessions (a mentoring lead's): ticks 3 to 9 were nobody's.
  recorder.reset();
  recorder.start();
  push({10, 11, 12});
  recorder.drain();
  EXPECT_EQ(recorder.missed(), 0u);
  EXPECT_EQ(recorder.takeProfile().size(), 3u);
}

TEST(Recorder, PenDownTriggerRecordsFromTouchDownToALongLift) {
  SpscRing<TickSample> ring(4096);
  Recorder recorder(ring, RecorderConfig{.trigger = RecordTrigger::kPenDown, .nominal_period_s = 1e-3, .pen_up_stop_s = 0.1},
                    ProfileMetadata{});
  recorder.start();
  for (int i = 0; i < 1000; ++i) {
    Sample s;
    s.t_s = i * 1e-3;
    s.pen_down = (i >= 100 && i < 300) || (i >= 350 && i < 500);  // a short lift, then a long one
    ASSERT_TRUE(ring.tryPush(TickSample{static_cast<std::uint64_t>(i), s}));
  }
  recorder.drain();
  const HapticProfile p = recorder.takeProfile();
  EXPECT_EQ(p.size(), 500u);  // samples 100 to 599: stops 100 ms into the long lift
  EXPECT_EQ(p.metadata().extra.at("t_origin_s"), "0.1");
}

TEST(Recorder, StoppedBeforeATickItKeepsEveryEarlierSampleItTakesLate) {
  SpscRing<TickSample> ring(4096);
  Recorder recorder(ring, RecorderConfig{.nominal_period_s = 1e-3}, ProfileMetadata{});
  recorder.start();
  const auto push = [&](int from, int to) {
    for (int i = from; i < to; ++i) {
      Sample s;
      s.t_s = i * 1e-3;
      ASSERT_TRUE(ring.tryPush(TickSample{static_cast<std::uint64_t>(i), s}));
    }
  };
  push(0, 200);
  recorder.drain();
  push(200, 500);            // the consumer falls behind: 300 samples wait in the ring
  recorder.stopBefore(450);  // the trial ends at tick 450
  push(500, 600);
  recorder.drain();
  const HapticProfile p = recorder.takeProfile();
  ASSERT_EQ(p.size(), 450u) << "every sample before the stop, none after";
  EXPECT_NEAR(p.samples().back().t_s, 0.449, 1e-12);
  // stop() is immediate: what the consumer has not taken yet is not kept.
  Recorder immediate(ring, RecorderConfig{.nominal_period_s = 1e-3}, ProfileMetadata{});
  immediate.start();
  push(600, 700);
  immediate.stop();
  immediate.drain();
  EXPECT_EQ(immediate.takeProfile().size(), 0u);
}

TEST(Recorder, KeepsOnlyItsLoopTimeWindowWhenArmedBeforeIt) {
  SpscRing<TickSample> ring(4096);
  Recorder recorder(ring, RecorderConfig{.nominal_period_s = 1e-3, .window_begin_s = 0.3, .window_end_s = 0.8},
                    ProfileMetadata{});
  recorder.start();
  for (int i = 0; i < 1000; ++i) {
    Sample s;
    s.t_s = i * 1e-3 + ((i % 3) - 1) * 1e-7;  // time stamps a little off the multiples
    ASSERT_TRUE(ring.tryPush(TickSample{static_cast<std::uint64_t>(i), s}));
    if (i == 700) {
      recorder.drain();
      EXPECT_FALSE(recorder.reachedEnd());
    }
  }
  recorder.drain();
  EXPECT_TRUE(recorder.reachedEnd());
  EXPECT_FALSE(recorder.writingOver());  // the window's end is not the end rule's
  const HapticProfile p = recorder.takeProfile();
  EXPECT_EQ(p.size(), 500u);  // samples 300 to 799
  EXPECT_NEAR(std::stod(p.metadata().extra.at("t_origin_s")), 0.3, 1e-6);
}

}  // namespace
}  // namespace hattr::session
