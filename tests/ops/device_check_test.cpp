// The device check as a library call (issue 41): the callbacks a front end gives it, and one
// result with its toJson.

#include "hattr/ops/device_check.hpp"

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"

namespace hattr::ops {
namespace {

TEST(DeviceCheck, ASimulatedPenIsDescribedRunsTheForceAndTheAnswerDecides) {
  std::optional<DeviceDescription> described;
  std::string notice;
  bool asked = false;
  const DeviceCheckResult r = runDeviceCheck({.uri = "sim://pen",
                                              .seconds = 0.2,
                                              .opened = [&](const DeviceDescription& d) { described = d; },
                                              .announce = [&](const std::string& text) { notice = text; },
                                              .confirm = [&] {
                                                asked = true;
                                                return std::optional<bool>(false);
                                              }});
  ASSERT_TRUE(described.has_value());
  EXPECT_EQ(described->uri, "sim://pen");
  EXPECT_EQ(described->rate_hz, described->limits.nominal_rate_hz);
  EXPECT_NE(notice.find("0.2 N upward force"), std::string::npos) << notice;
  EXPECT_TRUE(asked);
  EXPECT_TRUE(r.force_reached) << r.commanded_N << " N commanded";
  EXPECT_NEAR(r.commanded_N, 0.2, 0.004);
  EXPECT_GT(r.pen_rise_m, 0.0) << "the upward force lifts the lightly held simulated pen";
  EXPECT_EQ(r.confirmed, std::optional<bool>(false));
  EXPECT_FALSE(r.ok()) << "the person did not feel it";
  const nlohmann::json json = r.toJson();
  EXPECT_EQ(json["ok"], false);
  EXPECT_EQ(json["force_test"]["confirmed"], false);
  EXPECT_EQ(json["clocking"], "host (simulatable)");
  EXPECT_EQ(json["ticks"].get<std::uint64_t>(), r.figures.ticks);
  EXPECT_EQ(json["verdicts"].size(), r.judgement.figures.size());
}

TEST(DeviceCheck, WithoutAConfirmationTheCommandedForceDecidesAndNothingIsAnnounced) {
  bool announced = false;
  const DeviceCheckResult r =
      runDeviceCheck({.uri = "sim://pen", .seconds = 0.2, .announce = [&](const std::string&) { announced = true; }});
  EXPECT_FALSE(announced) << "nobody is asked, so nobody is told";
  EXPECT_FALSE(r.confirmed.has_value());
  EXPECT_EQ(r.ok(), r.force_reached && r.judgement.overall != servo::Verdict::kFail);
  EXPECT_TRUE(r.toJson()["force_test"]["confirmed"].is_null());
}

TEST(DeviceCheck, AForcePastTheContinuousForceOrABadDurationIsRefused) {
  EXPECT_THROW((void)runDeviceCheck({.uri = "sim://pen", .seconds = 0.2, .force_N = 3.0}), InputError);
  EXPECT_THROW((void)runDeviceCheck({.uri = "sim://pen", .seconds = 0.0}), InputError);
  EXPECT_THROW((void)runDeviceCheck({.uri = "usb://phantom"}), InputError);
}

}  // namespace
}  // namespace hattr::ops
