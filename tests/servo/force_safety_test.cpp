#include "hattr/servo/force_safety.hpp"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "support/thread_sanitizer.hpp"

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

namespace hattr::servo {
namespace {

/// A number from the edges of what a double can be: zero, denormals, the tiny, the ordinary,
/// the absurd, the largest, infinities and NaN, with random signs and magnitudes.
double extremeNumber(std::mt19937_64& random) {
  std::uniform_int_distribution<int> kind(0, 11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double sign = unit(random) < 0.0 ? -1.0 : 1.0;
  switch (kind(random)) {
    case 0: return 0.0;
    case 1: return sign * std::numeric_limits<double>::denorm_min();
    case 2: return sign * 1e-310 * std::abs(unit(random));
    case 3: return unit(random);
    case 4: return 10.0 * unit(random);
    case 5: return 1e6 * unit(random);
    case 6: return sign * 1e154 * (1.0 + std::abs(unit(random)));
    case 7: return sign * std::numeric_limits<double>::max();
    case 8: return sign * std::numeric_limits<double>::infinity();
    case 9: return std::numeric_limits<double>::quiet_NaN();
    case 10: return sign * std::pow(10.0, 628.0 * std::abs(unit(random)) - 320.0);
    default: return 0.05 * unit(random);
  }
}

TEST(ForceSafety, IsTotalForEveryInputFiniteWithinTheLimitOrALatchedFault) {
  HATTR_STARTS_NO_THREAD();
  const std::uint64_t seed = std::random_device{}();
  std::mt19937_64 random(seed);
  // A pool of extreme numbers, drawn from by a cheap generator: 10^7 cases in about a second.
  std::vector<double> pool(1u << 16);
  for (double& x : pool) x = extremeNumber(random);
  std::uint64_t state = seed | 1u;
  const auto next = [&] {  // xorshift64*
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return state * 0x2545F4914F6CDD1DULL;
  };
  const auto pick = [&] { return pool[next() >> 48]; };
  const auto vector = [&] { return Vec3(pick(), pick(), pick()); };

  ForceSafety safety(SafetyConfig{.ramp_time_s = 0.0}, DeviceLimits{});
  const double limit = safety.maxForce_N() * (1.0 + 1e-9);
  std::uint64_t faults = 0, passed_force = 0;
  for (int i = 0; i < 10'000'000; ++i) {
    // Mostly ordinary positions and periods, sometimes extreme ones.
    const std::uint64_t r = next();
    const Vec3 p = (r & 15u) != 0 ? Vec3(0.01, -0.02, 0.005) : vector();
    const double dt = (r & 240u) != 0 ? 1e-3 : pick();
    const Vec3 out = safety.filter(vector(), vector(), p, dt);
    if (!(out.allFinite() && out.norm() <= limit)) {
      FAIL() << "seed " << seed << ", case " << i << ": output " << out.transpose() << " (limit " << limit << " N)";
    }
    if (safety.fault() != SafetyFault::kNone) {
      if (out.norm() != 0.0) FAIL() << "seed " << seed << ", case " << i << ": a latched fault must output zero";
      ++faults;
      safety.clearFault();
    } else if (out.norm() > 0.0) {
      ++passed_force;
    }
  }
  // Both outcomes happened: the inputs really covered the sane and the absurd.
  EXPECT_GT(faults, 1'000'000u) << "seed " << seed;
  EXPECT_GT(passed_force, 10'000u) << "seed " << seed;
}

TEST(ForceSafety, AHugeFiniteGuidanceLatchesAFaultInsteadOfOverflowing) {
  ForceSafety safety(SafetyConfig{.ramp_time_s = 0.0}, DeviceLimits{});
  const Vec3 out = safety.filter(Vec3::Zero(), Vec3(1e154, 0.0, 0.0), Vec3::Zero(), 1e-3);
  EXPECT_EQ(out, Vec3::Zero());
  EXPECT_EQ(safety.fault(), SafetyFault::kNonFiniteForce);
  // And it stays zero until cleared; then ordinary forces pass again.
  EXPECT_EQ(safety.filter(Vec3::Zero(), Vec3(0.5, 0.0, 0.0), Vec3::Zero(), 1e-3), Vec3::Zero());
  safety.clearFault();
  EXPECT_GT(safety.filter(Vec3::Zero(), Vec3(0.5, 0.0, 0.0), Vec3::Zero(), 1e-3).norm(), 0.0);
}

}  // namespace
}  // namespace hattr::servo
