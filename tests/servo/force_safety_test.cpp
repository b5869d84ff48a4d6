#include "hattr/servo/force_safety.hpp"

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"

namespace hattr::servo {
namespace {

SafetyConfig noRamp() {
  SafetyConfig c;
  c.ramp_time_s = 0.0;
  return c;
}

TEST(ForceSafety, RateLimitBoundsEveryStep) {
  SafetyConfig config = noRamp();
  config.max_rate_N_per_s = 1000.0;  // 1 N per ms
  ForceSafety safety(config, device::DeviceLimits{});
  const Vec3 f1 = safety.filter(Vec3(1.5, 0, 0), Vec3::Zero(), 1e-3);
  EXPECT_NEAR(f1.x(), 1.0, 1e-12);
  const Vec3 f2 = safety.filter(Vec3(1.5, 0, 0), Vec3::Zero(), 1e-3);
  EXPECT_NEAR(f2.x(), 1.5, 1e-12);
}

TEST(ForceSafety, ClampKeepsTheDirection) {
  SafetyConfig config = noRamp();
  config.max_rate_N_per_s = 1e9;
  ForceSafety safety(config, device::DeviceLimits{});
  const Vec3 f = safety.filter(Vec3(3.0, 4.0, 0.0), Vec3::Zero(), 1e-3);
  EXPECT_NEAR(f.norm(), device::DeviceLimits{}.continuous_force_N, 1e-12);
  EXPECT_NEAR(f.y() / f.x(), 4.0 / 3.0, 1e-12);
}

TEST(ForceSafety, ClampGivesWayWithTheGuidanceFirstSoThePaperKeepsItsSupport) {
  SafetyConfig config = noRamp();
  config.max_rate_N_per_s = 1e9;
  ForceSafety safety(config, device::DeviceLimits{});  // 1.75 N
  const Vec3 paper(0.0, 0.0, 1.5), guidance(2.0, 0.0, 0.0);
  const Vec3 f = safety.filter(paper, guidance, Vec3::Zero(), 1e-3);
  EXPECT_NEAR(f.z(), 1.5, 1e-12);                                  // the paper's support intact
  EXPECT_NEAR(f.x(), std::sqrt(1.75 * 1.75 - 1.5 * 1.5), 1e-12);   // the guidance takes what is left
  EXPECT_NEAR(f.norm(), 1.75, 1e-12);
  // A paper force beyond the limit alone is clamped itself, without guidance.
  const Vec3 g = safety.filter(Vec3(0.0, 0.0, 3.0), guidance, Vec3::Zero(), 1e-3);
  EXPECT_NEAR(g.z(), 1.75, 1e-12);
  EXPECT_NEAR(g.x(), 0.0, 1e-12);
}

TEST(ForceSafety, SoftWallsPushBackIntoTheWorkspace) {
  SafetyConfig config = noRamp();
  config.max_rate_N_per_s = 1e9;
  device::DeviceLimits limits;
  ForceSafety safety(config, limits);
  const Vec3 outside(limits.workspace_max_m.x() - config.wall_margin_m + 0.001, 0.0, 0.0);
  const Vec3 f = safety.filter(Vec3::Zero(), outside, 1e-3);
  EXPECT_NEAR(f.x(), -config.wall_stiffness_N_per_m * 0.001, 1e-9);
  EXPECT_EQ(safety.filter(Vec3::Zero(), Vec3::Zero(), 1e-3), Vec3::Zero());
}

TEST(ForceSafety, RejectsNonsenseSettings) {
  SafetyConfig config;
  config.ramp_time_s = -1.0;
  EXPECT_THROW(ForceSafety(config, device::DeviceLimits{}), InputError);
}

}  // namespace
}  // namespace hattr::servo
