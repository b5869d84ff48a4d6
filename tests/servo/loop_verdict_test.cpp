// The verdicts of servo-check and devices check on loops run in simulated time: a clean loop
// passes, a stalled one warns, jitter and overruns warn (most ticks over a period fail), a
// latched fault and lost samples fail, link loss warns (issue 38).

#include "hattr/servo/loop_verdict.hpp"

#include <limits>

#include <gtest/gtest.h>

#include "hattr/device/simulated_device.hpp"

namespace hattr::servo {
namespace {

using namespace std::chrono_literals;

class ConstantGuidance final : public GuidanceController {
 public:
  Vec3 force = Vec3::Zero();
  Vec3 compute(const PenState&, const ContactForces&, double) noexcept override { return force; }
};

struct VerdictRig {
  explicit VerdictRig(std::size_t ring = 1u << 16)
      : device(device::SimulatedPenParams{}, nullptr), loop(device, ServoConfig{.sample_ring_capacity = ring}) {
    loop.setGuidance(&guidance);
  }
  device::SimulatedDevice device;
  ConstantGuidance guidance;
  ServoLoop loop;
};

Verdict verdictOf(const LoopJudgement& j, const std::string& figure) {
  for (const auto& f : j.figures) {
    if (f.name == figure) return f.verdict;
  }
  ADD_FAILURE() << "no figure " << figure;
  return Verdict::kFail;
}

TEST(LoopVerdict, ACleanLoopPassesEveryFigure) {
  VerdictRig rig;
  rig.loop.runSimulated(2000);
  const LoopJudgement j = judgeLoop(rig.loop);
  for (const auto& f : j.figures) EXPECT_EQ(f.verdict, Verdict::kPass) << f.name << " = " << f.value << " (" << f.rule << ")";
  EXPECT_EQ(j.overall, Verdict::kPass);
  EXPECT_EQ(verdictName(j.overall), "PASS");
}

TEST(LoopVerdict, AStalledLoopWarnsAndSaysWhy) {
  VerdictRig rig;
  rig.loop.runSimulated(500);
  rig.loop.delaySimulated(20ms);  // the host held the loop 20 ms: beyond the 10 ms watchdog
  rig.loop.runSimulated(500);
  const LoopJudgement j = judgeLoop(rig.loop);
  EXPECT_EQ(verdictOf(j, "stalls"), Verdict::kWarn);
  EXPECT_EQ(verdictOf(j, "faults"), Verdict::kPass);
  EXPECT_EQ(j.overall, Verdict::kWarn);
}

// The period error is measured on a real-time or device clock (simulated ticks have none), so
// the jitter rule is checked on the figures of a clean simulated run with the p99 set.
TEST(LoopVerdict, JitterBeyondATenthOfThePeriodWarns) {
  VerdictRig rig;
  rig.loop.runSimulated(1000);
  LoopFigures figures = figuresOf(rig.loop);
  EXPECT_DOUBLE_EQ(figures.period_us, 1000.0);
  figures.period_error_p99_us = 100.0;  // 10 % of the period at 1 kHz
  EXPECT_EQ(verdictOf(judgeLoop(figures), "period_error_p99_us"), Verdict::kPass);
  figures.period_error_p99_us = 101.0;
  const LoopJudgement j = judgeLoop(figures);
  EXPECT_EQ(verdictOf(j, "period_error_p99_us"), Verdict::kWarn);
  EXPECT_EQ(j.overall, Verdict::kWarn);
  // Most ticks longer than a period: the pipeline cannot keep its rate.
  figures.period_error_p99_us = 0.0;
  figures.overruns = figures.ticks / 2 + 1;
  EXPECT_EQ(verdictOf(judgeLoop(figures), "overrun_share_percent"), Verdict::kFail);
  figures.overruns = figures.ticks / 100;
  EXPECT_EQ(verdictOf(judgeLoop(figures), "overrun_share_percent"), Verdict::kWarn);
}

TEST(LoopVerdict, ALatchedFaultOrLostSamplesFail) {
  VerdictRig faulty;
  faulty.loop.runSimulated(100);
  faulty.guidance.force = Vec3(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
  faulty.loop.runSimulated(10);
  LoopJudgement j = judgeLoop(faulty.loop);
  EXPECT_EQ(verdictOf(j, "faults"), Verdict::kFail);
  EXPECT_EQ(j.overall, Verdict::kFail);

  VerdictRig unread(64);  // nobody drains a 64-sample ring
  unread.loop.runSimulated(200);
  j = judgeLoop(unread.loop);
  EXPECT_EQ(verdictOf(j, "dropped_samples"), Verdict::kFail);
  EXPECT_EQ(verdictName(j.overall), "FAIL");
}

TEST(LoopVerdict, LinkLossBeyondOnePercentWarns) {
  VerdictRig rig;
  rig.loop.runSimulated(100);
  device::LinkStats link;
  link.states_received = 990;
  link.states_lost = 10;
  LoopJudgement j = judgeLoop(rig.loop);
  judgeLink(link, j);
  EXPECT_EQ(verdictOf(j, "link_loss_percent"), Verdict::kPass);
  link.states_lost = 30;
  j = judgeLoop(rig.loop);
  judgeLink(link, j);
  EXPECT_EQ(verdictOf(j, "link_loss_percent"), Verdict::kWarn);
  EXPECT_EQ(j.overall, Verdict::kWarn);
}

}  // namespace
}  // namespace hattr::servo
