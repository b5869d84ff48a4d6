#include "hattr/render/paper_renderer.hpp"

#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "support/no_allocation.hpp"
#include "support/test_support.hpp"

namespace hattr::render {
namespace {

PaperParams plainPaper() {
  PaperParams p;
  p.texture.sigma = 0.0;
  return p;
}

PenState penAt(Vec3 p, Vec3 v = Vec3::Zero()) {
  PenState pen;
  pen.p_WT = p;
  pen.v_WT = v;
  return pen;
}

// ---- Normal force --------------------------------------------------------------------------

TEST(PaperRenderer, NormalForceIsSpringPlusDamperClampedAtZero) {
  const PaperParams params = plainPaper();
  const double k = params.contact.stiffness_N_per_m;
  const double c = params.contact.damping_N_s_per_m;
  for (const double depth : {1e-5, 1e-4, 5e-4, 2e-3}) {
    for (const double rate : {-0.5, -0.01, 0.0, 0.01, 0.2}) {  // δ̇ > 0: pressing further in
      PaperRenderer paper(params);
      ContactForces out;
      paper.render(penAt(Vec3(0.01, 0.02, -depth), Vec3(0, 0, -rate)), 1e-3, out);
      const double expected = std::max(0.0, k * depth + c * rate);
      EXPECT_NEAR(out.f_on_pen_W.z(), expected, 1e-12) << "depth " << depth << " rate " << rate;
      EXPECT_GE(out.f_on_pen_W.z(), 0.0);
      EXPECT_TRUE(out.in_contact);
      EXPECT_EQ(out.f_on_paper_W, -out.f_on_pen_W);
    }
  }
  PaperRenderer paper(params);
  ContactForces out;
  paper.render(penAt(Vec3(0, 0, 1e-4), Vec3(0, 0, -1.0)), 1e-3, out);  // above the paper
  EXPECT_FALSE(out.in_contact);
  EXPECT_EQ(out.f_on_pen_W, Vec3::Zero());
}

TEST(PaperRenderer, AxialForceFollowsTheInclination) {
  PaperRenderer paper(plainPaper());
  ContactForces out;
  PenState pen = penAt(Vec3(0, 0, -1e-3));
  pen.has_tilt = true;
  pen.altitude_rad = std::numbers::pi / 6;  // 30°: F_r = F·sin θ = F/2
  paper.render(pen, 1e-3, out);
  EXPECT_NEAR(paper.detail().axial_N, 2.0 * paper.detail().normal_N, 1e-12);
  pen.has_tilt = false;  // no tilt: the configured writing angle (60°)
  paper.render(pen, 1e-3, out);
  EXPECT_NEAR(paper.detail().axial_N * std::sin(std::numbers::pi / 3), paper.detail().normal_N, 1e-12);
}

// ---- Friction ----------------------------------------------------------------------------

TEST(PaperRenderer, SticksInsideTheStaticConeThenSlidesOnTheDynamicCone) {
  const PaperParams params = plainPaper();
  PaperRenderer paper(params);
  const double depth = 1e-3;
  const double fn = params.contact.stiffness_N_per_m * depth;
  const double kt = params.tangential_stiffness_N_per_m;
  ContactForces out;
  bool broke_loose = false;
  double tangential_before_break = 0.0;
  // Push the tip along +x in 1 µm steps at constant depth.
  for (int step = 0; step <= 1000; ++step) {
    const double x = step * 1e-6;
    paper.render(penAt(Vec3(x, 0, -depth)), 1e-3, out);
    const double ft = out.f_on_pen_W.head<2>().norm();
    if (!paper.detail().sliding) {
      EXPECT_NEAR(ft, kt * x, 1e-9) << "stuck: a spring back to the touch-down point";
      EXPECT_LE(ft, params.friction.static_coefficient * fn + 1e-12);
      tangential_before_break = ft;
    } else {
      if (!broke_loose) {
        EXPECT_GT(kt * x, params.friction.static_coefficient * fn) << "broke loose before μs·Fn";
        EXPECT_GT(tangential_before_break, 0.9 * params.friction.static_coefficient * fn);
        broke_loose = true;
      }
      EXPECT_NEAR(ft, params.friction.dynamic_coefficient * fn, 1e-9);
    }
    // Friction always opposes the motion (+x).
    EXPECT_LE(out.f_on_pen_W.x(), 0.0);
  }
  EXPECT_TRUE(broke_loose);
}

TEST(PaperRenderer, OnATableTheNormalIsThePressAndOnlyInPlaneForcesAreRendered) {
  // A planar pen (docs/hardware.md): the table holds it up at z = 0 (or 1 mm up when lifted);
  // the normal reaction is the pressure reading in newtons, the friction cones scale with it.
  PaperParams params = plainPaper();
  params.normal_from_pressure = true;
  PaperRenderer paper(params);
  ContactForces out;
  PenState pen = penAt(Vec3(0, 0, 0.0));
  paper.render(pen, 1e-3, out);
  EXPECT_FALSE(out.in_contact) << "no pressure reading: the pen is lifted";
  pen.has_pressure = true;
  pen.pressure_raw = 0.03;
  pen.p_WT.z() = 0.001;
  paper.render(pen, 1e-3, out);
  EXPECT_FALSE(out.in_contact) << "the device says lifted (a press under its contact threshold)";
  pen.pressure_raw = 0.8;
  const double kt = params.tangential_stiffness_N_per_m;
  for (int step = 0; step <= 1000; ++step) {
    pen.p_WT = Vec3(step * 1e-6, 0, 0);
    paper.render(pen, 1e-3, out);
    ASSERT_TRUE(out.in_contact);
    EXPECT_EQ(out.f_on_pen_W.z(), 0.0) << "the table gives the normal itself";
    EXPECT_NEAR(out.f_on_paper_W.z(), -0.8, 1e-12) << "the pen still presses on the paper";
    if (!paper.detail().sliding) {
      EXPECT_NEAR(out.f_on_pen_W.x(), -kt * step * 1e-6, 1e-9);
    }
  }
  ASSERT_TRUE(paper.detail().sliding);
  EXPECT_NEAR(out.f_on_pen_W.head<2>().norm(), params.friction.dynamic_coefficient * 0.8, 1e-9);
  EXPECT_NEAR(paper.detail().normal_N, 0.8, 1e-12);
}

TEST(PaperRenderer, OnATableAPenAtRestOnASlopeFeelsOnlyTheTiltOfTheNormal) {
  // The tip lies on the relief (it cannot sink into it); at rest, friction pulls nowhere and the
  // in-plane force is the normal's tilt (force shading), whatever height the device reports.
  PaperParams params = plainPaper();
  params.normal_from_pressure = true;
  PaperRenderer paper(params, HeightField::fromFunction(41, 41, Vec3(-0.01, -0.01, 0.0), 0.0005,
                                                        [](double x, double) { return 0.2 * (x + 0.01); }));
  PenState pen = penAt(Vec3(0.005, 0.0, 0.0));
  pen.has_pressure = true;
  pen.pressure_raw = 1.0;
  ContactForces out;
  for (int i = 0; i < 3; ++i) paper.render(pen, 1e-3, out);
  ASSERT_TRUE(out.in_contact);
  const Vec3 n = paper.relief().surfaceAt(0.005, 0.0).normal_W;
  EXPECT_GT(std::abs(n.x()), 0.1) << "the slope tilts the normal";
  EXPECT_NEAR((out.f_on_pen_W.head<2>() - 1.0 * n.head<2>()).norm(), 0.0, 1e-9);
}

TEST(PaperRenderer, SlidingStopsWhenThePullDropsInsideTheDynamicCone) {
  PaperRenderer paper(plainPaper());
  ContactForces out;
  for (int step = 0; step <= 1000; ++step) paper.render(penAt(Vec3(step * 1e-6, 0, -1e-3)), 1e-3, out);
  ASSERT_TRUE(paper.detail().sliding);
  // Stop moving: the proxy trails the tip by μd·Fn/kt, inside the static cone: it sticks.
  paper.render(penAt(Vec3(1000 * 1e-6, 0, -1e-3)), 1e-3, out);
  EXPECT_FALSE(paper.detail().sliding);
  // Reverse: friction flips to oppose the new motion once the proxy is passed.
  for (int step = 1000; step >= 0; --step) paper.render(penAt(Vec3(step * 1e-6, 0, -1e-3)), 1e-3, out);
  EXPECT_GT(out.f_on_pen_W.x(), 0.0);
}

TEST(PaperRenderer, ContactQueryNeverAllocates) {
  PaperParams params;
  PaperRenderer paper(params, HeightField::paperGrain(0.05, 128, 1e-5, 5e-4, 3));
  ContactForces out;
  paper.render(penAt(Vec3(0, 0, -1e-3)), 1e-3, out);
  const test::NoAllocationScope scope;
  for (int i = 0; i < 10'000; ++i) {
    const double a = i * 1e-3;
    paper.render(penAt(Vec3(0.01 * std::cos(a), 0.01 * std::sin(a), -5e-4)), 1e-3, out);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

// ---- Stability bounds ------------------------------------------------------------------------

TEST(PaperStability, ClampsToColgatesBoundAndReportsIt) {
  DeviceLimits limits;  // b = 1 N·s/m, 1000 N/m maximum
  PaperParams params;
  params.contact.stiffness_N_per_m = 5000.0;
  params.contact.damping_N_s_per_m = 3.0;
  const auto changes = clampToDevice(params, limits, 1000.0);
  ASSERT_FALSE(changes.empty());
  EXPECT_THAT(changes.front(), ::testing::HasSubstr("paper stiffness 5000 N/m -> "));
  EXPECT_THAT(changes.front(), ::testing::HasSubstr(": device maximum stiffness"));
  const double t = 1e-3;
  EXPECT_LT(params.contact.stiffness_N_per_m * t / 2 + params.contact.damping_N_s_per_m, limits.damping_N_s_per_m);
  EXPECT_LE(params.tangential_stiffness_N_per_m * t / 2, limits.damping_N_s_per_m);

  PaperParams fine;  // the defaults are already passive on the default device
  EXPECT_TRUE(clampToDevice(fine, limits, 1000.0).empty());
  // At 10 kHz the same device allows more stiffness by Colgate, but not beyond its maximum.
  EXPECT_DOUBLE_EQ(passiveStiffnessBound(limits, 10'000.0, 0.0), limits.max_stiffness_N_per_m);
  EXPECT_NEAR(passiveStiffnessBound(limits, 1000.0, 0.8), 2 * (1.0 - 0.8) / 1e-3, 1e-9);
}

TEST(PaperRenderer, RefusesOutOfRangeParameters) {
  PaperParams p;
  p.friction.dynamic_coefficient = 0.5;  // above static
  try {
    PaperRenderer paper(p);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("friction.dynamic (<= friction.static): expected a number in [0, 0.3], got 0.5"));
  }
}

}  // namespace
}  // namespace hattr::render
