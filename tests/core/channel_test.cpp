#include "hattr/core/channel.hpp"

#include <gtest/gtest.h>

namespace hattr {
namespace {

TEST(Channel, EveryChannelIsFoundByItsOwnName) {
  for (const auto& info : allChannels()) {
    const auto found = channelFromName(info.name);
    ASSERT_TRUE(found.has_value()) << info.name;
    EXPECT_EQ(*found, info.channel);
    EXPECT_EQ(channelInfo(info.channel).name, info.name);
  }
}

TEST(Channel, ForceMagnitudeAnswersToItsAlias) {
  EXPECT_EQ(channelFromName("fmag"), Channel::kForceMagnitude);
  EXPECT_EQ(channelFromName("|f|"), Channel::kForceMagnitude);
  EXPECT_FALSE(channelFromName("force").has_value());
}

TEST(Channel, DerivedChannelsAreComputedFromTheSample) {
  Sample s;
  s.v_WT = Vec3(3.0, 4.0, 0.0);
  s.f_user_W = Vec3(0.0, -6.0, -8.0);
  EXPECT_DOUBLE_EQ(channelValue(s, Channel::kSpeed), 5.0);
  EXPECT_DOUBLE_EQ(channelValue(s, Channel::kForceMagnitude), 10.0);
  EXPECT_DOUBLE_EQ(channelValue(s, Channel::kFz), -8.0);
}

TEST(Channel, RawChannelsAreNeededOnlyWhenAbsent) {
  EXPECT_TRUE(needsRawChannel(Channel::kPressure, RawChannels{}));
  EXPECT_FALSE(needsRawChannel(Channel::kPressure, RawChannels{.pressure = true}));
  EXPECT_TRUE(needsRawChannel(Channel::kAltitude, RawChannels{.pressure = true}));
  EXPECT_FALSE(needsRawChannel(Channel::kX, RawChannels{}));
}

}  // namespace
}  // namespace hattr
