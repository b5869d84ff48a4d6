// The servo check as a library call (issue 41): what `hattr servo-check` prints comes from one
// result and its toJson.

#include "hattr/ops/servo_check.hpp"

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"

namespace hattr::ops {
namespace {

TEST(ServoCheck, ASimulatedPenRunsTheFloorAndTheLoopAndJudgesThem) {
  int progress_calls[3] = {0, 0, 0};
  const ServoCheckResult r = runServoCheck({.rate_hz = 1000.0,
                                            .seconds = 0.3,
                                            .realtime = {.policy = servo::RealtimePolicy::kSkip},
                                            .progress = [&](int run, double) { ++progress_calls[run]; }});
  EXPECT_GT(progress_calls[1], 0) << "the floor's run reported progress";
  EXPECT_GT(progress_calls[2], 0) << "the loop's run reported progress";
  EXPECT_GT(r.floor.count(), 0u);
  EXPECT_GT(r.figures.ticks, 100u);
  EXPECT_EQ(r.samples_consumed + r.figures.dropped_samples, r.figures.ticks);
  EXPECT_FALSE(r.link.has_value()) << "sim://pen is not behind a network link";
  EXPECT_FALSE(r.judgement.figures.empty());
  const nlohmann::json json = r.toJson();
  EXPECT_EQ(json["device"], "sim://pen");
  EXPECT_EQ(json["world"], "defaults");
  EXPECT_EQ(json["loop"]["ticks"].get<std::uint64_t>(), r.figures.ticks);
  EXPECT_EQ(json["verdict"], std::string(servo::verdictName(r.judgement.overall)));
  EXPECT_EQ(json["verdicts"].size(), r.judgement.figures.size());
  EXPECT_FALSE(json.contains("link"));
}

TEST(ServoCheck, BadOptionsAreRefusedBeforeAnythingRuns) {
  EXPECT_THROW((void)runServoCheck({.rate_hz = 0.0}), InputError);
  EXPECT_THROW((void)runServoCheck({.seconds = -1.0}), InputError);
  EXPECT_THROW((void)runServoCheck({.seconds = 0.01, .device = "sim://arm"}), InputError);
  EXPECT_THROW((void)servo::parseRealtimePolicy("always"), InputError);
}

}  // namespace
}  // namespace hattr::ops
