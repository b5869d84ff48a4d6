#include "hattr/guidance/training_guidance.hpp"

#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/core/passivity.hpp"
#include "support/test_support.hpp"

namespace hattr::guidance {
namespace {

using ::testing::HasSubstr;

/// An expert profile: a smooth curve over 2 s at 1 kHz, pressing with a varying force.
HapticProfile expertProfile() {
  HapticProfile p;
  for (int i = 0; i <= 2000; ++i) {
    Sample s;
    s.t_s = i * 1e-3;
    const double a = 3.0 * s.t_s;
    s.p_WT = Vec3(0.02 * std::sin(a), 0.01 * std::sin(2 * a), -0.0015);
    s.v_WT = Vec3(0.06 * std::cos(a), 0.06 * std::cos(2 * a), 0.0);
    s.f_user_W = Vec3(0.2 * std::cos(a), 0.1, -1.0 - 0.5 * std::sin(a));
    s.pen_down = s.in_contact = true;
    p.append(s);
  }
  return p;
}

PenState penOn(const ReferencePoint& r, double t) {
  PenState pen;
  pen.t_s = t;
  pen.p_WT = r.p_WT;
  pen.v_WT = r.v_WT;
  return pen;
}

TEST(TrainingGuidance, TraineeExactlyOnTheReferenceGetsNoAssistance) {
  const auto reference = std::make_shared<ReferenceTrajectory>(expertProfile(), 1000.0);
  for (const TrainingMode mode : {TrainingMode::kPositionControl, TrainingMode::kForceControl}) {
    TrainingGuidance guidance(reference, GuidanceConfig{.mode = mode});
    for (std::size_t i = 0; i < reference->size(); ++i) {
      const ReferencePoint& r = (*reference)[i];
      ContactForces contact{.f_on_pen_W = -r.f_W, .f_on_paper_W = r.f_W, .in_contact = true};
      const Vec3 f = guidance.compute(penOn(r, static_cast<double>(i) * 1e-3), contact, 1e-3);
      ASSERT_LT(f.norm(), 1e-9) << modeName(mode) << " at sample " << i;
    }
  }
}

TEST(TrainingGuidance, PositionControlIsThePaperPdLawInThePlane) {
  const auto reference = std::make_shared<ReferenceTrajectory>(expertProfile(), 1000.0);
  TrainingGuidance guidance(reference, GuidanceConfig{.mode = TrainingMode::kPositionControl});
  const ReferencePoint r = (*reference)[500];
  PenState pen = penOn(r, 0.5);
  pen.p_WT += Vec3(0.002, -0.001, 0.003);
  pen.v_WT += Vec3(0.01, 0.0, 0.0);
  const Vec3 f = guidance.compute(pen, ContactForces{}, 1e-3);
  EXPECT_NEAR(f.x(), 350.0 * -0.002 + 170.0 * -0.01, 1e-9);  // 0.35 N/mm, 0.17 N·s/mm in SI
  EXPECT_NEAR(f.y(), 350.0 * 0.001, 1e-9);
  EXPECT_EQ(f.z(), 0.0);
}

TEST(TrainingGuidance, ForceControlPushesTowardTheExpertForceWhenTheUserPressesTooLightly) {
  const auto reference = std::make_shared<ReferenceTrajectory>(expertProfile(), 1000.0);
  GuidanceConfig config{.mode = TrainingMode::kForceControl};
  config.lift_fade_s = 0.0;
  TrainingGuidance guidance(reference, config);
  const ReferencePoint r = (*reference)[0];
  const Vec3 light = 0.5 * r.f_W;  // pressing half as hard
  const Vec3 f = guidance.compute(penOn(r, 0.0), ContactForces{.f_on_paper_W = light, .in_contact = true}, 1e-3);
  EXPECT_NEAR(f.z(), 0.5 * (r.f_W.z() - light.z()), 1e-12);  // Kp·e on the first tick (no ė yet)
  EXPECT_LT(f.z(), 0.0);                                      // into the paper: press harder
}

TEST(TrainingGuidance, ModeSwitchStepsNoMoreThanTheCrossFadeAllows) {
  const auto reference = std::make_shared<ReferenceTrajectory>(expertProfile(), 1000.0);
  GuidanceConfig config{.mode = TrainingMode::kBasic};
  config.crossfade_s = 0.1;
  TrainingGuidance guidance(reference, config);
  PenState pen = penOn((*reference)[0], 0.0);
  pen.p_WT += Vec3(0.004, 0.0, 0.0);  // 4 mm off: PCONTROL wants 1.4 N
  pen.t_s = -1.0;                    // before the start: the reference holds still
  (void)guidance.compute(pen, ContactForces{}, 1e-3);
  guidance.switchMode(TrainingMode::kPositionControl);
  Vec3 last = Vec3::Zero();
  const double target = 350.0 * 0.004;
  for (int tick = 1; tick <= 150; ++tick) {
    const Vec3 f = guidance.compute(pen, ContactForces{}, 1e-3);
    EXPECT_LE((f - last).norm(), target * 1e-3 / 0.1 + 1e-12) << "tick " << tick;
    last = f;
  }
  EXPECT_NEAR(last.norm(), target, 1e-9);
}

TEST(ReferencePlayer, ProgressIndexingNeverMovesBackward) {
  const std::uint64_t seed = test::testSeed(3);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> jitter(0.0, 0.003);
  const ReferenceTrajectory reference(expertProfile(), 1000.0);
  ReferencePlayer player(reference, PlaybackConfig{.indexing = Indexing::kProgress});
  double last = 0.0;
  for (int tick = 0; tick < 3000; ++tick) {
    // A noisy trainee wandering around the path, sometimes going back.
    const double along = 1000.0 + 900.0 * std::sin(tick * 0.004);
    Vec3 p = reference.at(along).p_WT + Vec3(jitter(rng), jitter(rng), 0.0);
    const ReferenceCue cue = player.at(tick * 1e-3, p);
    ASSERT_GE(cue.index, last) << "seed " << seed << " tick " << tick;
    last = cue.index;
  }
}

TEST(ReferencePlayer, ProgressMatchesTimeIndexingAtTheExpertsPace) {
  const ReferenceTrajectory reference(expertProfile(), 1000.0);
  ReferencePlayer by_time(reference, PlaybackConfig{.indexing = Indexing::kTime});
  ReferencePlayer by_progress(reference, PlaybackConfig{.indexing = Indexing::kProgress});
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const double t = static_cast<double>(i) * 1e-3;
    const Vec3 p = reference[i].p_WT;
    ASSERT_NEAR(by_progress.at(t, p).index, by_time.at(t, p).index, 1.0) << "sample " << i;
  }
}

TEST(ReferencePlayer, HoldsBeforeTheStartAndFadesOutAfterTheEnd) {
  const ReferenceTrajectory reference(expertProfile(), 1000.0);
  ReferencePlayer player(reference, PlaybackConfig{.end_hold_s = 0.2, .fade_out_s = 0.3});
  EXPECT_EQ(player.at(-0.5, Vec3::Zero()).phase, ReferenceCue::Phase::kBefore);
  EXPECT_EQ(player.at(-0.5, Vec3::Zero()).point.p_WT, reference[0].p_WT);
  EXPECT_EQ(player.at(1.0, Vec3::Zero()).weight, 1.0);
  EXPECT_EQ(player.at(2.1, Vec3::Zero()).weight, 1.0);           // end at 2.0 s, holding
  EXPECT_NEAR(player.at(2.35, Vec3::Zero()).weight, 0.5, 1e-9);  // half faded
  EXPECT_EQ(player.at(3.0, Vec3::Zero()).weight, 0.0);
}

TEST(ClampGains, ClampsThePapersGainsWhereTheBoundSaysAndReportsIt) {
  const DeviceLimits limits;  // b = 1 N·s/m, 1000 N/m, 5 N·s/m at 1 kHz
  const WorldImpedance world;  // paper 600 N/m, 0.1 N·s/m; friction spring 500 N/m
  GuidanceConfig config;
  const auto changes = clampGains(config, limits, 1000.0, world);
  // PCONTROL: Kd 170 N·s/m is far beyond the device; Kp 350 N/m fits beside the 500 N/m
  // friction spring (850 <= 1000), leaving Colgate room 1 − 850·T/2 = 0.575 N·s/m, of which
  // the clamp takes 80 %.
  EXPECT_EQ(config.position.kp_N_per_m, 350.0);
  EXPECT_NEAR(config.position.kd_N_s_per_m, 0.8 * (1.0 - 850.0 * 1e-3 / 2), 1e-12);
  // ALPHA: Kp = 0.5 fits ((1 + 0.5)·600 = 900 N/m); Kd·K + Kp·C may use 80 % of
  // 1 − 900·T/2 − 0.1 = 0.45 N·s/m.
  EXPECT_NEAR(config.force.kp, 0.5, 1e-12);
  EXPECT_NEAR(config.force.kd_s, (0.8 * 0.45 - 0.5 * 0.1) / 600.0, 1e-12);
  ASSERT_FALSE(changes.empty());
  EXPECT_EQ(changes[0],
            "PCONTROL Kd 170 N·s/m -> 0.46 N·s/m: device maximum damping, then Colgate's passivity bound b > K·T/2 + B");
  EXPECT_THAT(changes.back(), HasSubstr("ALPHA Kd 0.1 s -> 0.0005167 s"));
  for (const auto& line : changes) EXPECT_THAT(line, ::testing::Not(HasSubstr("ALPHA Kp")));
  // With everything passive already, nothing changes.
  GuidanceConfig gentle;
  gentle.position = {.kp_N_per_m = 100.0, .kd_N_s_per_m = 0.1};
  gentle.force = {.kp = 0.2, .kd_s = 0.0};
  EXPECT_TRUE(clampGains(gentle, limits, 1000.0, world).empty());
}

TEST(TrainingGuidance, RefusesBadModesAndSettings) {
  EXPECT_EQ(parseMode("Alpha"), TrainingMode::kForceControl);
  try {
    (void)parseMode("beta");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "mode: expected one of basic, pcontrol, alpha, mentor-observe, mentor-position, "
                           "mentor-force, mentor-bilateral, channel, error-augmentation, noise, playback, fading, "
                           "assist-as-needed, partial-then-full, got \"beta\"");
  }
  // The mentored modes by name; the recorded reference gives them no force (the live expert does).
  EXPECT_EQ(parseMode("mentor-force"), TrainingMode::kMentorForce);
  EXPECT_EQ(modeName(TrainingMode::kMentorObserve), "MENTOR-OBSERVE");
  EXPECT_TRUE(isMentored(TrainingMode::kMentorBilateral));
  EXPECT_FALSE(isMentored(TrainingMode::kForceControl));
  TrainingGuidance mentored(nullptr, GuidanceConfig{.mode = TrainingMode::kMentorPosition});
  PenState pen;
  pen.p_WT = Vec3(0.01, 0.0, 0.0);
  EXPECT_EQ(mentored.compute(pen, ContactForces{}, 1e-3), Vec3::Zero());
  EXPECT_THROW(TrainingGuidance(nullptr, GuidanceConfig{.mode = TrainingMode::kForceControl}), InputError);
  EXPECT_THROW(parseIndexing("space"), InputError);
}

}  // namespace
}  // namespace hattr::guidance
