// The strategies beyond the paper's (issue 36): each force law against its formula, the
// catalog's parameters and ranges, no allocation on the tick, and the passivity clamps.

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/guidance/strategy_schedule.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "support/no_allocation.hpp"

namespace hattr::guidance {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

/// A straight stroke along x over `seconds` at 1 kHz (10 mm/s), pressing 1 N, with a sideways force.
HapticProfile straightStroke(int seconds = 2) {
  HapticProfile p;
  for (int i = 0; i <= 1000 * seconds; ++i) {
    Sample s;
    s.t_s = i * 1e-3;
    s.p_WT = Vec3(0.01 * s.t_s, 0.0, -0.001);
    s.v_WT = Vec3(0.01, 0.0, 0.0);
    s.f_user_W = Vec3(0.1, -0.05, -1.0);
    s.pen_down = s.in_contact = true;
    p.append(s);
  }
  return p;
}

PenState penAt(double t_s, const Vec3& p, const Vec3& v = Vec3::Zero()) {
  PenState pen;
  pen.t_s = t_s;
  pen.p_WT = p;
  pen.v_WT = v;
  return pen;
}

struct Rig {
  explicit Rig(TrainingMode mode, const std::vector<std::string>& parameters = {}) {
    GuidanceConfig config{.mode = mode};
    std::vector<StrategySetting> settings;
    for (const auto& p : parameters) settings.push_back(parseStrategySetting(p));
    setStrategyParameters(config, mode, settings);
    guidance = std::make_unique<TrainingGuidance>(reference, config);
  }
  std::shared_ptr<const ReferenceTrajectory> reference =
      std::make_shared<ReferenceTrajectory>(straightStroke(), 1000.0);
  std::unique_ptr<TrainingGuidance> guidance;
};

TEST(Channel, NoForceInsideTheTubeASpringAndDamperTowardItsWallOutside) {
  Rig rig(TrainingMode::kChannel, {"half_width_mm=2", "kd_N_s_per_mm=0.01"});
  // At t = 1 s the reference is at x = 10 mm; a pen 1.5 mm beside the path is inside.
  EXPECT_EQ(rig.guidance->compute(penAt(1.0, Vec3(0.010, 0.0015, 0.0)), ContactForces{}, 1e-3), Vec3::Zero());
  // 5 mm beside it, moving outward at 20 mm/s: back by 350 N/m × 3 mm plus 10 N·s/m × 20 mm/s.
  const Vec3 f = rig.guidance->compute(penAt(1.001, Vec3(0.010, 0.005, 0.0), Vec3(0.0, 0.02, 0.0)), ContactForces{}, 1e-3);
  EXPECT_NEAR(f.y(), -(350.0 * 0.003 + 10.0 * 0.02), 1e-9);
  EXPECT_NEAR(f.x(), 0.0, 1e-9);
  EXPECT_EQ(f.z(), 0.0);
  // Ahead of the expert's point along the path but on it: the channel is the path, not the moment.
  EXPECT_EQ(rig.guidance->compute(penAt(1.002, Vec3(0.013, 0.0, 0.0)), ContactForces{}, 1e-3), Vec3::Zero());
}

TEST(ErrorAugmentation, PushesAwayFromTheExpertsPointInProportionUpToItsSaturation) {
  Rig rig(TrainingMode::kErrorAugmentation, {"gain_N_per_mm=0.2", "saturation_mm=5"});
  // At t = 0.5 s the expert is at x = 5 mm: a pen 2 mm behind and 1 mm above is pushed further.
  const Vec3 f = rig.guidance->compute(penAt(0.5, Vec3(0.003, 0.001, 0.004)), ContactForces{}, 1e-3);
  EXPECT_NEAR(f.x(), 200.0 * -0.002, 1e-9);
  EXPECT_NEAR(f.y(), 200.0 * 0.001, 1e-9);
  EXPECT_EQ(f.z(), 0.0) << "in the plane only";
  // 30 mm off counts as 5 mm.
  const Vec3 far = rig.guidance->compute(penAt(0.501, Vec3(0.005, 0.030, 0.0)), ContactForces{}, 1e-3);
  EXPECT_NEAR(far.norm(), 200.0 * 0.005, 1e-6);
  EXPECT_GT(far.y(), 0.0);
}

TEST(Playback, PushesTheExpertsForceOpenLoopWhateverThePenDoes) {
  Rig rig(TrainingMode::kPlayback, {"gain=0.5"});
  const Vec3 expert = (*rig.reference)[700].f_W;
  for (const Vec3& p : {Vec3(0.0, 0.0, 0.01), Vec3(0.05, -0.02, 0.0)}) {
    rig.guidance->startTrial(0.0);
    const Vec3 f = rig.guidance->compute(penAt(0.7, p), ContactForces{}, 1e-3);
    EXPECT_NEAR((f - 0.5 * expert).norm(), 0.0, 1e-12) << p.transpose();
  }
}

TEST(Noise, IsARepeatableBandLimitedForceOfTheAskedSizeInThePlane) {
  const auto run = [](std::uint64_t seed) {
    GuidanceConfig config{.mode = TrainingMode::kNoise};
    setStrategyParameters(config, TrainingMode::kNoise, std::vector<StrategySetting>{{"rms_N", "0.4"}, {"cutoff_hz", "5"}});
    config.noise.seed = seed;
    // A reference as long as the run: the noise fades out with the reference's end, as every law.
    TrainingGuidance guidance(std::make_shared<ReferenceTrajectory>(straightStroke(201), 1000.0), config);
    std::vector<Vec3> forces;
    for (int i = 0; i < 200'000; ++i) forces.push_back(guidance.compute(penAt(i * 1e-3, Vec3::Zero()), {}, 1e-3));
    return forces;
  };
  const std::vector<Vec3> a = run(7), b = run(7), c = run(8);
  EXPECT_EQ(a, b) << "the same seed, the same force";
  EXPECT_NE(a, c);
  double sq_x = 0.0, sq_y = 0.0, lag = 0.0;
  for (std::size_t i = 1; i < a.size(); ++i) {
    EXPECT_EQ(a[i].z(), 0.0);
    sq_x += a[i].x() * a[i].x();
    sq_y += a[i].y() * a[i].y();
    lag += a[i].x() * a[i - 1].x();
  }
  const double n = static_cast<double>(a.size() - 1);
  // 200 s of a 5 Hz first-order process: about 6 000 independent stretches, so the RMS is within
  // a few percent; its lag-1 correlation is 1 − α, α = dt / (dt + 1/(2π·5 Hz)).
  EXPECT_NEAR(std::sqrt(sq_x / n), 0.4, 0.04);
  EXPECT_NEAR(std::sqrt(sq_y / n), 0.4, 0.04);
  const double alpha = 1e-3 / (1e-3 + 1.0 / (2.0 * std::numbers::pi * 5.0));
  EXPECT_NEAR(lag / sq_x, 1.0 - alpha, 0.005);
}

TEST(Strategies, NoTickOfAnyStrategyAllocatesOrLocks) {
  for (const TrainingMode mode : {TrainingMode::kChannel, TrainingMode::kErrorAugmentation, TrainingMode::kNoise,
                                  TrainingMode::kPlayback, TrainingMode::kPositionControl, TrainingMode::kForceControl,
                                  TrainingMode::kFading, TrainingMode::kAssistAsNeeded, TrainingMode::kPartialThenFull}) {
    Rig rig(mode);
    (void)rig.guidance->compute(penAt(0.0, Vec3::Zero()), ContactForces{}, 1e-3);  // warm up outside the scope
    const test::NoAllocationScope scope;
    for (int i = 1; i < 3000; ++i) {
      (void)rig.guidance->compute(penAt(i * 1e-3, Vec3(0.01 * i * 1e-3, 0.004, 0.0)), ContactForces{}, 1e-3);
    }
    rig.guidance->switchMode(TrainingMode::kNoise);
    for (int i = 3000; i < 3200; ++i) (void)rig.guidance->compute(penAt(i * 1e-3, Vec3::Zero()), ContactForces{}, 1e-3);
    EXPECT_EQ(scope.allocations(), 0u) << modeName(mode);
    if (test::lockHookActive()) {
      EXPECT_EQ(scope.locks(), 0u) << modeName(mode);
    }
  }
}

TEST(Strategies, TheirSpringsAreClampedToWhatTheDeviceRendersPassively) {
  // The default pen: at most 1000 N/m, of which the friction spring takes 500 in the plane.
  const DeviceLimits limits;
  GuidanceConfig config;
  setStrategyParameter(config, TrainingMode::kChannel, "kp_N_per_mm", 1.5);
  setStrategyParameter(config, TrainingMode::kErrorAugmentation, "gain_N_per_mm", 0.8);
  const std::vector<std::string> changes = clampGains(config, limits, 1000.0, WorldImpedance{});
  const auto mentions = [&](const char* what) {
    for (const auto& c : changes) {
      if (c.starts_with(what)) return true;
    }
    return false;
  };
  EXPECT_TRUE(mentions("CHANNEL Kp"));
  EXPECT_TRUE(mentions("ERROR-AUGMENTATION gain"));
  EXPECT_LE(config.channel.kp_N_per_m, 500.0);
  EXPECT_LE(config.augmentation.gain_N_per_m, 500.0);
  EXPECT_GT(config.augmentation.gain_N_per_m, 0.0);
}

TEST(StrategyCatalog, ListsEveryModeWithItsParametersAndRefusesValuesOutsideTheirRanges) {
  const auto& catalog = strategyCatalog();
  ASSERT_EQ(catalog.size(), static_cast<std::size_t>(kLastMode) + 1);
  for (std::size_t i = 0; i < catalog.size(); ++i) {
    EXPECT_EQ(static_cast<std::size_t>(catalog[i].mode), i);
    EXPECT_FALSE(catalog[i].plain_name.empty());
    EXPECT_FALSE(catalog[i].source.empty());
    EXPECT_EQ(parseMode(modeName(catalog[i].mode)), catalog[i].mode);
    // Each parameter's default is what a default configuration holds, within its range.
    for (const auto& p : catalog[i].parameters) {
      EXPECT_LE(p.min, p.default_value);
      EXPECT_LE(p.default_value, p.max);
      EXPECT_NEAR(strategyParameter(GuidanceConfig{}, catalog[i].mode, p.name), p.default_value,
                  1e-12 * std::max(1.0, p.default_value))
          << modeName(catalog[i].mode) << " " << p.name;
    }
  }
  GuidanceConfig config;
  setStrategyParameter(config, TrainingMode::kChannel, "half_width_mm", 1.5);
  EXPECT_DOUBLE_EQ(config.channel.half_width_m, 0.0015);
  EXPECT_THAT([&] { setStrategyParameter(config, TrainingMode::kChannel, "half_width_mm", 50.0); },
              ThrowsMessage<InputError>(HasSubstr("CHANNEL half_width_mm: expected 0 to 20 mm, got 50")));
  EXPECT_THAT([&] { setStrategyParameter(config, TrainingMode::kChannel, "width", 1.0); },
              ThrowsMessage<InputError>(HasSubstr("CHANNEL: no parameter \"width\": expected one of half_width_mm")));
  EXPECT_THAT([&] { setStrategyParameter(config, TrainingMode::kBasic, "gain", 1.0); },
              ThrowsMessage<InputError>(HasSubstr("it has no parameters")));
  EXPECT_THAT([] { (void)parseStrategySetting("rms_N"); }, ThrowsMessage<InputError>(HasSubstr("expected KEY=VALUE")));
  EXPECT_THAT([] { (void)parseStrategySetting("rms_N="); }, ThrowsMessage<InputError>(HasSubstr("expected KEY=VALUE")));
  EXPECT_EQ(parseStrategySetting("rms_N=+0.25"), (StrategySetting{"rms_N", "+0.25"}));
  setStrategyParameters(config, TrainingMode::kNoise, std::vector{parseStrategySetting("rms_N=+0.25")});
  EXPECT_EQ(config.noise.rms_N, 0.25);
  EXPECT_THAT([&] { setStrategyParameters(config, TrainingMode::kNoise, std::vector{parseStrategySetting("rms_N=0.3x")}); },
              ThrowsMessage<InputError>(HasSubstr("NOISE rms_N: expected a number from 0 to 2 N, got \"0.3x\"")));
  EXPECT_THAT([&] { setStrategyParameters(config, TrainingMode::kNoise, std::vector{parseStrategySetting("rms_N=1e400")}); },
              ThrowsMessage<InputError>(HasSubstr("NOISE rms_N: expected 0 to 2 N, got inf")));
  EXPECT_THAT([&] {
    setStrategyParameters(config, TrainingMode::kNoise, std::vector<StrategySetting>{{"rms_N", "0.1"}, {"rms_N", "0.2"}});
  }, ThrowsMessage<InputError>(HasSubstr("NOISE rms_N: given twice")));
  EXPECT_THAT([] { (void)parseMode("chanel"); }, ThrowsMessage<InputError>(HasSubstr("channel, error-augmentation")));
  // A choice by its name, in any case; its index as a number; nothing else.
  setStrategyParameter(config, TrainingMode::kFading, "base", std::string_view("ALPHA"));
  EXPECT_EQ(config.fading.base, TrainingMode::kForceControl);
  EXPECT_EQ(strategyParameterText(config, TrainingMode::kFading, "base"), "alpha");
  setStrategyParameter(config, TrainingMode::kFading, "by", 1.0);
  EXPECT_EQ(config.fading.by, FadingConfig::By::kPerformance);
  EXPECT_THAT([&] { setStrategyParameter(config, TrainingMode::kAssistAsNeeded, "base", std::string_view("noise")); },
              ThrowsMessage<InputError>(HasSubstr("ASSIST-AS-NEEDED base: expected one of pcontrol, alpha, got \"noise\"")));
  EXPECT_THAT([&] { setStrategyParameter(config, TrainingMode::kFading, "by", 2.0); },
              ThrowsMessage<InputError>(HasSubstr("FADING by: expected one of trials, performance, got 2")));
}

// ---- The scheduled strategies ---------------------------------------------------------------

TEST(ScheduledStrategies, PlayTheirTrialsLawAtItsGain) {
  // The same pen state under the plain law and under each scheduled strategy playing it.
  const PenState pen = penAt(0.5, Vec3(0.003, 0.004, -0.001), Vec3(0.004, -0.01, 0.0));  // outside the channel
  ContactForces contact;
  contact.in_contact = true;
  contact.f_on_paper_W = Vec3(0.2, 0.1, -0.5);
  const auto force = [&](TrainingMode mode, const ScheduledLaw& scheduled) {
    GuidanceConfig config{.mode = mode};
    config.scheduled = scheduled;
    config.lift_fade_s = 0.0;  // ALPHA at full weight in contact from the first tick
    TrainingGuidance guidance(std::make_shared<ReferenceTrajectory>(straightStroke(), 1000.0), config);
    (void)guidance.compute(penAt(0.499, pen.p_WT, pen.v_WT), contact, 1e-3);
    return guidance.compute(pen, contact, 1e-3);
  };
  for (const TrainingMode law : {TrainingMode::kPositionControl, TrainingMode::kForceControl, TrainingMode::kChannel}) {
    const Vec3 plain = force(law, {});
    ASSERT_GT(plain.norm(), 0.01) << modeName(law);
    for (const TrainingMode mode : {TrainingMode::kFading, TrainingMode::kAssistAsNeeded, TrainingMode::kPartialThenFull}) {
      EXPECT_LT((force(mode, {law, 0.35}) - 0.35 * plain).norm(), 1e-12) << modeName(mode) << " " << modeName(law);
      EXPECT_EQ(force(mode, {law, 0.0}), Vec3::Zero());
    }
  }
  // The mailbox switches to no scheduled mode but the trial's own (its law and gain are that one's).
  {
    GuidanceConfig config{.mode = TrainingMode::kFading};
    TrainingGuidance guidance(std::make_shared<ReferenceTrajectory>(straightStroke(), 1000.0), config);
    EXPECT_FALSE(guidance.setParameter(kParameterMode, static_cast<double>(TrainingMode::kAssistAsNeeded)));
    EXPECT_TRUE(guidance.setParameter(kParameterMode, static_cast<double>(TrainingMode::kBasic)));
    EXPECT_TRUE(guidance.setParameter(kParameterMode, static_cast<double>(TrainingMode::kFading)));
  }
  // A scheduled law must be a plain one, its gain within 0 to 1.
  GuidanceConfig bad{.mode = TrainingMode::kFading};
  bad.scheduled = {TrainingMode::kFading, 0.5};
  EXPECT_THROW(TrainingGuidance(std::make_shared<ReferenceTrajectory>(straightStroke(), 1000.0), bad), InputError);
  bad.scheduled = {TrainingMode::kPositionControl, 1.5};
  EXPECT_THROW(TrainingGuidance(std::make_shared<ReferenceTrajectory>(straightStroke(), 1000.0), bad), InputError);
}

TEST(ScheduledStrategies, FadingFallsLinearlyOverTrialsOrByAStepAfterEachGoodTrial) {
  GuidanceConfig config;
  setStrategyParameters(config, TrainingMode::kFading,
                        std::vector<StrategySetting>{{"base", "alpha"}, {"start_gain", "1"}, {"end_gain", "0.2"},
                                                     {"trials", "5"}});
  const std::vector<double> errors(8, 0.001);
  // Trial n (from 0) of 5: 1 − 0.8·n/4, then 0.2 from the fifth on.
  for (std::size_t n = 0; n <= errors.size(); ++n) {
    const ScheduledLaw law = scheduleTrial(config, TrainingMode::kFading, std::span(errors).first(n));
    EXPECT_EQ(law.law, TrainingMode::kForceControl);
    EXPECT_NEAR(law.gain, n >= 4 ? 0.2 : 1.0 - 0.8 * static_cast<double>(n) / 4.0, 1e-12) << n;
  }
  // Reached at guided trial `trials`: with 1, at the first.
  GuidanceConfig at_once;
  setStrategyParameter(at_once, TrainingMode::kFading, "trials", 1.0);
  setStrategyParameter(at_once, TrainingMode::kFading, "end_gain", 0.3);
  EXPECT_EQ(scheduleTrial(at_once, TrainingMode::kFading, {}).gain, 0.3);
  // By performance: a 0.25 step after each trial of at most 1.5 mm, none after a worse one.
  setStrategyParameters(config, TrainingMode::kFading,
                        std::vector<StrategySetting>{{"by", "performance"}, {"step", "0.25"}, {"threshold_mm", "1.5"}});
  const std::vector<double> mixed{0.001, 0.003, 0.0015, INFINITY, 0.0002, 0.0001, 0.0001};
  const std::vector<double> expected{1.0, 0.75, 0.75, 0.5, 0.5, 0.25, 0.2, 0.2};
  for (std::size_t n = 0; n <= mixed.size(); ++n) {
    EXPECT_NEAR(scheduleTrial(config, TrainingMode::kFading, std::span(mixed).first(n)).gain, expected[n], 1e-12) << n;
  }
}

TEST(ScheduledStrategies, AssistAsNeededFollowsTheErrorWithForgetting) {
  GuidanceConfig config;
  setStrategyParameters(config, TrainingMode::kAssistAsNeeded,
                        std::vector<StrategySetting>{{"start_gain", "0.6"}, {"forgetting", "0.8"},
                                                     {"error_gain_per_mm", "0.1"}, {"deadband_mm", "0.5"}});
  const std::vector<double> errors{0.0025, 0.0004, 0.0001, 0.02, 0.0005};
  // g₁ = 0.6; g_{n+1} = clamp(0.8·g_n + 0.1/mm · max(0, e_n − 0.5 mm), 0, 1).
  double g = 0.6;
  for (std::size_t n = 0; n <= errors.size(); ++n) {
    const ScheduledLaw law = scheduleTrial(config, TrainingMode::kAssistAsNeeded, std::span(errors).first(n));
    EXPECT_EQ(law.law, TrainingMode::kPositionControl);
    EXPECT_NEAR(law.gain, g, 1e-12) << n;
    if (n < errors.size()) g = std::clamp(0.8 * g + 100.0 * std::max(0.0, errors[n] - 0.0005), 0.0, 1.0);
  }
  EXPECT_NEAR(scheduleTrial(config, TrainingMode::kAssistAsNeeded, std::span(errors).first(4)).gain, 1.0, 1e-12)
      << "20 mm of error: full assistance";
  // A trial with nothing written (an infinite error) gives full assistance; with no error gain,
  // none added: never a gain that is not a number.
  const std::vector<double> nothing{INFINITY};
  EXPECT_EQ(scheduleTrial(config, TrainingMode::kAssistAsNeeded, nothing).gain, 1.0);
  setStrategyParameter(config, TrainingMode::kAssistAsNeeded, "error_gain_per_mm", 0.0);
  EXPECT_NEAR(scheduleTrial(config, TrainingMode::kAssistAsNeeded, nothing).gain, 0.8 * 0.6, 1e-12);
}

TEST(ScheduledStrategies, PartialThenFullSwitchesFromTheChannelToTheGuidedPath) {
  GuidanceConfig config;
  setStrategyParameter(config, TrainingMode::kPartialThenFull, "partial_trials", 2.0);
  const std::vector<double> errors(4, 0.001);
  for (std::size_t n = 0; n <= errors.size(); ++n) {
    const ScheduledLaw law = scheduleTrial(config, TrainingMode::kPartialThenFull, std::span(errors).first(n));
    EXPECT_EQ(law.law, n < 2 ? TrainingMode::kChannel : TrainingMode::kPositionControl) << n;
    EXPECT_EQ(law.gain, 1.0);
  }
}

TEST(ScheduledStrategies, TrackingErrorIsTheRmsDistanceOfThePenDownSamplesToThePath) {
  const ReferenceTrajectory reference(straightStroke(), 1000.0);
  HapticProfile trial;
  for (int i = 0; i <= 100; ++i) {
    Sample s;
    s.t_s = i * 1e-2;
    // Along the path, 1 mm beside it then 3 mm; the pen up (ignored) 10 mm away in between.
    s.p_WT = Vec3(0.0002 * i, i < 50 ? 0.001 : 0.003, 0.0);
    s.pen_down = i % 10 != 5;
    if (!s.pen_down) s.p_WT.y() = 0.01;
    trial.append(s);
  }
  // 45 samples at 1 mm (0..49 less 5 up), 46 at 3 mm (50..100 less 5 up).
  EXPECT_NEAR(trackingErrorRms(reference, trial), std::sqrt((45 * 1e-6 + 46 * 9e-6) / 91.0), 1e-12);
  HapticProfile nothing;
  for (int i = 0; i < 10; ++i) nothing.append(Sample{.t_s = i * 1e-2});
  EXPECT_EQ(trackingErrorRms(reference, nothing), INFINITY);
}

}  // namespace
}  // namespace hattr::guidance
