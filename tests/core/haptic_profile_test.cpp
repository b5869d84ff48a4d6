#include "hattr/core/haptic_profile.hpp"

#include <cmath>
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;

Sample sampleAt(double t, double x = 0.0) {
  Sample s;
  s.t_s = t;
  s.p_WT = Vec3(x, 2.0 * x, 0.0);
  return s;
}

std::string appendError(HapticProfile& profile, const Sample& s) {
  try {
    profile.append(s);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(HapticProfile, DurationAndRateComeFromTheTimeStamps) {
  HapticProfile profile;
  for (int i = 0; i <= 1000; ++i) profile.append(sampleAt(0.5 + i * 1e-3));
  EXPECT_NEAR(profile.duration_s(), 1.0, 1e-12);
  EXPECT_NEAR(profile.measuredRate_hz(), 1000.0, 1e-6);
}

TEST(HapticProfile, RejectsTimeThatDoesNotIncrease) {
  HapticProfile profile;
  profile.append(sampleAt(1.0));
  EXPECT_THAT(appendError(profile, sampleAt(1.0)), HasSubstr("time must increase strictly"));
  EXPECT_THAT(appendError(profile, sampleAt(0.5)), HasSubstr("expected > 1 s, got 0.5 s"));
  EXPECT_EQ(profile.size(), 1u);
}

TEST(HapticProfile, RejectsNonFiniteValuesNamingTheChannel) {
  HapticProfile profile;
  Sample s = sampleAt(0.0);
  s.f_user_W.z() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(appendError(profile, s), HasSubstr("channel fz: expected a finite number, got nan"));
  EXPECT_TRUE(profile.empty());
}

TEST(HapticProfile, IgnoresRawChannelsItDoesNotCarry) {
  HapticProfile profile;  // no pressure channel: its field is not checked
  Sample s = sampleAt(0.0);
  s.pressure_raw = std::numeric_limits<double>::infinity();
  EXPECT_NO_THROW(profile.append(s));
  HapticProfile with_pressure({}, RawChannels{.pressure = true});
  EXPECT_THAT(appendError(with_pressure, s), HasSubstr("channel pressure"));
}

TEST(HapticProfile, GivesChannelsByNameAndRefusesUnknownOnes) {
  HapticProfile profile;
  for (int i = 0; i < 4; ++i) profile.append(sampleAt(i, i));
  EXPECT_EQ(profile.channel("y"), (std::vector<double>{0.0, 2.0, 4.0, 6.0}));
  EXPECT_EQ(profile.range(Channel::kX).max, 3.0);
  try {
    (void)profile.channel("force");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown channel \"force\": expected one of t, x, y"));
  }
  EXPECT_THROW((void)profile.channel("pressure"), InputError);
}

TEST(FiniteDifferences, AreExactOnAParabolaWithUnevenSteps) {
  std::vector<Sample> samples;
  for (double t : {0.0, 0.1, 0.25, 0.27, 0.5, 0.9}) {
    Sample s;
    s.t_s = t;
    s.p_WT = Vec3(3.0 * t * t - t, 2.0 * t, 1.0);
    samples.push_back(s);
  }
  fillVelocityByFiniteDifferences(samples);
  for (std::size_t i = 1; i + 1 < samples.size(); ++i) {
    EXPECT_NEAR(samples[i].v_WT.x(), 6.0 * samples[i].t_s - 1.0, 1e-12) << "i=" << i;
    EXPECT_NEAR(samples[i].v_WT.y(), 2.0, 1e-12);
    EXPECT_NEAR(samples[i].v_WT.z(), 0.0, 1e-12);
  }
}

TEST(Utc, TimeStampIsIso8601) {
  const std::string now = utcNowIso8601();
  ASSERT_EQ(now.size(), 20u) << now;
  EXPECT_EQ(now[4], '-');
  EXPECT_EQ(now[10], 'T');
  EXPECT_EQ(now.back(), 'Z');
}

}  // namespace
}  // namespace hattr
