// A recording says what happened to it: the pen through the paper, the device held at its
// force limit, the pen outside the workspace (issue 38), judged sample by sample, counted with
// the time of the first, written into the metadata and counted as a disturbance.

#include <cmath>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/session/trial_physics.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::session {
namespace {

// 1 s at 1 kHz, at rest 1 mm under a flat paper, with `edit` applied to each sample.
template <typename Edit>
HapticProfile restingProfile(Edit edit) {
  HapticProfile p;
  for (int i = 0; i <= 1000; ++i) {
    Sample s;
    s.t_s = i * 1e-3;
    s.p_WT = Vec3(0.0, 0.0, -0.001);
    edit(i, s);
    p.append(s);
  }
  return p;
}

const DeviceLimits kLimits{};  // the default desktop pen: 1.75 N continuous, ±80 × ±60 × ±60 mm
constexpr double kForceLimit_N = 1.75;

TEST(TrialPhysics, ACleanRecordingHasNoEvent) {
  const auto p = restingProfile([](int, Sample& s) { s.f_cmd_W = Vec3(0.0, 0.0, 1.0); });
  const PhysicalEvents e = judgeRecording(p, kLimits, kForceLimit_N, render::HeightField{});
  EXPECT_FALSE(e.any());
  EXPECT_EQ(describePhysicalEvents(e), "");
}

TEST(TrialPhysics, ThePenDeeperThanTheBoundIsCountedOncePerEpisodeWithItsFirstTimeAndDepth) {
  // Two dips: 5 mm from 0.2 s to 0.3 s, 12 mm from 0.6 s to 0.65 s; 2.9 mm elsewhere at 0.8 s.
  const auto p = restingProfile([](int i, Sample& s) {
    if (i >= 200 && i < 300) s.p_WT.z() = -0.005;
    if (i >= 600 && i < 650) s.p_WT.z() = -0.012;
    if (i == 800) s.p_WT.z() = -0.0029;
  });
  const PhysicalEvents e = judgeRecording(p, kLimits, kForceLimit_N, render::HeightField{});
  EXPECT_EQ(e.penetration.count, 2u);
  EXPECT_DOUBLE_EQ(e.penetration.first_s, 0.2);
  EXPECT_NEAR(e.penetration.worst, 0.012, 1e-12);
  EXPECT_EQ(e.saturation.count, 0u);
  EXPECT_EQ(e.workspace.count, 0u);
  EXPECT_EQ(describePhysicalEvents(e), "the pen 12.0 mm under the paper at 0.200 s, 2 times");
}

TEST(TrialPhysics, TheDepthIsMeasuredFromTheReliefUnderThePen) {
  // A surface 4 mm high everywhere: the pen at z = 0 is 4 mm into it.
  const render::HeightField raised =
      render::HeightField::fromFunction(21, 21, Vec3(-0.1, -0.1, 0.0), 0.01, [](double, double) { return 0.004; });
  const auto p = restingProfile([](int, Sample& s) { s.p_WT.z() = 0.0; });
  EXPECT_EQ(judgeRecording(p, kLimits, kForceLimit_N, render::HeightField{}).penetration.count, 0u);
  const PhysicalEvents e = judgeRecording(p, kLimits, kForceLimit_N, raised);
  EXPECT_EQ(e.penetration.count, 1u);
  EXPECT_NEAR(e.penetration.worst, 0.004, 1e-9);
}

TEST(TrialPhysics, TheForceLimitCountsOnlyWhenThePaperAsksForItLongerThanTheBound) {
  // The paper asks for the limit for 50 ms twice (no event), then for 150 ms from 0.5 s (one
  // event); the guidance alone drives the command to the limit from 0.8 s to 1 s (no event).
  const auto p = restingProfile([](int i, Sample& s) {
    const bool paper_at_limit = (i >= 100 && i < 150) || (i >= 200 && i < 250) || (i >= 500 && i < 650);
    s.f_user_W = Vec3(0.0, 0.0, paper_at_limit ? -2.0 * kForceLimit_N : -0.5);
    s.f_cmd_W = Vec3(0.0, 0.0, paper_at_limit ? kForceLimit_N : 0.5);
    if (i >= 800) s.f_cmd_W = Vec3(kForceLimit_N, 0.0, 0.0);
  });
  const PhysicalEvents e = judgeRecording(p, kLimits, kForceLimit_N, render::HeightField{});
  EXPECT_EQ(e.saturation.count, 1u);
  EXPECT_DOUBLE_EQ(e.saturation.first_s, 0.5);
  EXPECT_NEAR(e.saturation.worst, 0.149, 1e-9);
}

TEST(TrialPhysics, LeavingTheWorkspaceIsCountedWithTheFarthestDistance) {
  const auto p = restingProfile([](int i, Sample& s) {
    if (i >= 400 && i < 420) s.p_WT.x() = 0.08 + 0.001 * (i - 399);
  });
  const PhysicalEvents e = judgeRecording(p, kLimits, kForceLimit_N, render::HeightField{});
  EXPECT_EQ(e.workspace.count, 1u);
  EXPECT_DOUBLE_EQ(e.workspace.first_s, 0.4);
  EXPECT_NEAR(e.workspace.worst, 0.020, 1e-12);
  EXPECT_NE(describePhysicalEvents(e).find("20.0 mm outside the device's workspace at 0.400 s"), std::string::npos);
}

TEST(TrialPhysics, MetadataNamesOnlyTheEventsThatHappened) {
  PhysicalEvents e;
  e.saturation = {.count = 3, .first_s = 0.25, .worst = 0.5};
  ProfileMetadata m;
  notePhysicalEvents(e, m);
  EXPECT_EQ(m.extra.count("physical_penetration"), 0u);
  EXPECT_EQ(m.extra.count("physical_workspace"), 0u);
  EXPECT_EQ(m.extra.at("physical_force_saturation"), "3 first 0.25 worst 0.5");
}

// A hand script writing a line for 1 s while pressing `press_N` into the paper.
HapticProfile pressingScript(double press_N) {
  HapticProfile p;
  for (int i = 0; i <= 100; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.02 * s.t_s, 0.0, 0.0);
    s.v_WT = Vec3(0.02, 0.0, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -press_N);
    s.pen_down = true;
    p.append(s);
  }
  return p;
}

TrialResult runPressing(double press_N) {
  TrialEnvironment env("sim://pen", render::WorldConfig{}, 1000.0);
  device::ProfileHandScript hand(pressingScript(press_N));
  TrialSetup setup{.duration_s = 1.2};
  return runTrial(env, setup, hand);
}

// The hand rests on the paper: its fingers' reach is measured from the relief under the pen, not
// from the writing plane. Paper lying 8 mm under the plane is pressed as hard as flat paper (the
// fingers' press eases off only from 4 mm under the surface; from the plane it would be halved).
TEST(TrialPhysics, TheHandPressesPaperLyingUnderTheWritingPlaneAsHardAsFlatPaper) {
  const test::TempDir dir;
  test::writeText(dir / "low.pgm", "P2\n2 2\n255\n255 255\n255 255\n");
  const auto mean_press = [](const char* world_json, const std::filesystem::path& base) {
    TrialEnvironment env("sim://pen", render::parseWorldConfig(world_json, "w.json", base), 1000.0);
    device::ProfileHandScript hand(pressingScript(1.2));
    const TrialResult r = runTrial(env, TrialSetup{.duration_s = 1.2}, hand);
    double sum = 0.0;
    int n = 0;
    for (const Sample& s : r.profile.samples()) {
      if (s.t_s < 0.3 || !s.pen_down) continue;  // once the press has settled
      sum += -s.f_user_W.z();
      ++n;
    }
    return n > 0 ? sum / n : 0.0;
  };
  const double flat = mean_press(R"({"relief": {"kind": "flat"}})", dir.path());
  const double low = mean_press(
      R"({"relief": {"kind": "pgm", "file": "low.pgm", "size_m": 0.3, "height_scale_m": -0.008}})", dir.path());
  EXPECT_NEAR(flat, 1.2, 0.05) << "the script presses 1.2 N into the paper";
  EXPECT_NEAR(low, flat, 0.03 * flat) << "flat " << flat << " N, 8 mm under the plane " << low << " N";
}

// Through the whole pipeline: a hand pressing 1.2 N writes a clean trial; one pressing 20 N
// (past what the pen renders) sinks through the paper, and the recording says so.
TEST(TrialPhysics, ATrialWhoseHandPressesPastTheDeviceIsDisturbedAndMarked) {
  HATTR_STARTS_NO_THREAD();
  const TrialResult light = runPressing(1.2);
  EXPECT_FALSE(light.physics.any()) << describePhysicalEvents(light.physics);
  EXPECT_EQ(disturbanceOf(light), "");
  EXPECT_EQ(light.profile.metadata().extra.count("disturbed"), 0u);
  EXPECT_EQ(light.profile.metadata().extra.at("loop_stalls"), "0");

  const TrialResult heavy = runPressing(20.0);
  EXPECT_GE(heavy.physics.penetration.count, 1u);
  EXPECT_GT(heavy.physics.penetration.worst, 0.003);
  EXPECT_GE(heavy.physics.saturation.count, 1u);
  const std::string disturbed = disturbanceOf(heavy);
  EXPECT_NE(disturbed.find("under the paper"), std::string::npos) << disturbed;
  EXPECT_NE(disturbed.find("at its force limit"), std::string::npos) << disturbed;
  const auto& extra = heavy.profile.metadata().extra;
  EXPECT_EQ(extra.at("disturbed"), disturbed);
  EXPECT_EQ(extra.count("physical_penetration"), 1u);
  EXPECT_EQ(extra.count("physical_force_saturation"), 1u);
}

// Issue 38: a profile to be used as an expert, a reference or a hand script is checked against
// the device before use: a force past its continuous force, a span past its workspace, each
// with the numbers and the remedy.
TEST(TrialPhysics, AProfileThatPressesOrReachesPastTheDeviceIsRefusedBeforeUseWithTheRemedy) {
  const auto fine = restingProfile([](int, Sample& s) { s.f_user_W = Vec3(0.0, 0.0, -1.2); });
  EXPECT_TRUE(renderabilityProblems(fine, kLimits).empty());
  EXPECT_NO_THROW(checkRenderable(fine, kLimits, "expert.csv"));

  const auto heavy = restingProfile([](int i, Sample& s) { s.f_user_W = Vec3(0.0, 0.0, i == 700 ? -3.3 : -1.2); });
  const auto problems = renderabilityProblems(heavy, kLimits);
  ASSERT_EQ(problems.size(), 1u);
  for (const char* part : {"presses up to 3.30 N (at 0.700 s)", "continuous force of 1.75 N", "sink through",
                           "expected at most 1.75 N", "--scale-force 0.53", "pressure_max_N"}) {
    EXPECT_NE(problems[0].find(part), std::string::npos) << part << " in: " << problems[0];
  }
  try {
    checkRenderable(heavy, kLimits, "--reference heavy.csv");
    ADD_FAILURE() << "an expert pressing 3.3 N on a 1.75 N pen was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--reference heavy.csv: it presses up to 3.30 N", 0), 0u) << e.what();
  }

  // 200 mm wide on a pen whose workspace is 160 mm wide.
  const auto wide = restingProfile([](int i, Sample& s) { s.p_WT.x() = -0.1 + 2e-4 * i; });
  const auto too_wide = renderabilityProblems(wide, kLimits);
  ASSERT_EQ(too_wide.size(), 1u);
  EXPECT_NE(too_wide[0].find("spans 200.0 mm along x, more than the device's workspace of 160.0 mm"), std::string::npos)
      << too_wide[0];

  // 40 mm wide but at x = 90..130 mm (a tablet's corner as the origin): it fits, elsewhere.
  const auto off = restingProfile([](int i, Sample& s) { s.p_WT.x() = 0.09 + 4e-5 * i; });
  const auto off_paper = renderabilityProblems(off, kLimits);
  ASSERT_EQ(off_paper.size(), 1u);
  EXPECT_NE(off_paper[0].find("reaches x = 90.0 to 130.0 mm, outside the device's workspace of -80.0 to 80.0 mm"),
            std::string::npos)
      << off_paper[0];
  EXPECT_NE(off_paper[0].find("hattr profile convert IN OUT --centre"), std::string::npos) << off_paper[0];
  std::vector<Sample> moved = off.samples();
  const Vec3 shift = centreOnPaper(moved);
  EXPECT_NEAR(shift.x(), -0.11, 1e-12);
  EXPECT_TRUE(renderabilityProblems(HapticProfile::fromSamples({}, {}, std::move(moved), false), kLimits).empty());
}

// The paper's thickness (a world key) is the depth past which the pen has fallen through.
TEST(TrialPhysics, TheWorldsPaperThicknessIsTheFallThroughDepth) {
  const auto p = restingProfile([](int i, Sample& s) { s.p_WT.z() = i == 500 ? -0.004 : -0.001; });
  TrialEnvironment thin("sim://pen", render::parseWorldConfig(R"({"relief": {"kind": "flat"}})", "w.json"));
  TrialEnvironment thick("sim://pen",
                         render::parseWorldConfig(R"({"paper": {"thickness_m": 0.005}, "relief": {"kind": "flat"}})", "w.json"));
  EXPECT_EQ(thin.physicalBounds().paper_thickness_m, 0.003);
  EXPECT_EQ(judgeRecording(p, kLimits, kForceLimit_N, {}, thin.physicalBounds()).penetration.count, 1u);
  EXPECT_EQ(judgeRecording(p, kLimits, kForceLimit_N, {}, thick.physicalBounds()).penetration.count, 0u);
  EXPECT_THROW((void)render::parseWorldConfig(R"({"paper": {"thickness_m": 0}})", "w.json"), InputError);
}

}  // namespace
}  // namespace hattr::session
