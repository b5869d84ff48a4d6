// Record and play through the whole pipeline: simulated hands on the simulated pen, the
// paper, the training modes, the servo loop and the recorder.

#include <cmath>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/simulated_device.hpp"
#include "hattr/render/flat_paper.hpp"
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
