// When a trial ends: the pen lifted for long enough after writing began, the maximum
// duration, or a stop request (real time); and the study file's trial_end.

#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/session/study.hpp"
#include "hattr/session/trial.hpp"
#include "support/host_stalls.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::session {
namespace {

using ::testing::HasSubstr;

/// A hand writing a stroke with the pen down for `writing_s`, then lifting it 5 mm and holding
/// it there (a script holds its last point after its end).
HapticProfile writeThenLift(double writing_s, double total_s) {
  HapticProfile p;
  for (int i = 0; i * 0.01 <= total_s + 1e-9; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    const bool down = s.t_s < writing_s;
    const double x = 0.02 * std::min(s.t_s, writing_s) / writing_s;
    s.p_WT = Vec3(x, 0.0, down ? 0.0 : 0.005);
    s.v_WT = Vec3(down ? 0.02 / writing_s : 0.0, 0.0, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, down ? -1.2 : 0.0);
    s.pen_down = down;
    p.append(s);
  }
  return p;
}

render::WorldConfig flatWorld() {
  render::WorldConfig w;
  w.relief.kind = render::ReliefConfig::Kind::kFlat;
  return w;
}

TEST(TrialEnd, EndsThePenUpTimeAfterTheLastPenUpNotAtTheMaximum) {
  HATTR_STARTS_NO_THREAD();
  TrialEnvironment env("sim://pen", flatWorld(), 1000.0);
  device::ProfileHandScript hand(writeThenLift(1.0, 1.2));
  TrialSetup setup{.duration_s = 10.0, .pen_up_end_s = 0.5};
  const TrialResult r = runTrial(env, setup, hand);
  EXPECT_EQ(r.end_reason, "pen lifted");
  const auto& extra = r.profile.metadata().extra;
  EXPECT_EQ(extra.at("end_reason"), "pen lifted");
  // Writing began when the pen first touched the paper and ended when it left it, about when
  // the hand lifted it; the trial ended pen_up_end_s later, to the tick, with the pen up.
  EXPECT_GE(r.writing_begin_s, 0.0);
  EXPECT_LT(r.writing_begin_s, 0.2);
  EXPECT_GT(r.writing_end_s, 0.9);
  EXPECT_LT(r.writing_end_s, 1.3);
  EXPECT_NEAR(r.profile.samples().back().t_s, r.writing_end_s + 0.5, 1.5e-3);
  EXPECT_FALSE(r.profile.samples().back().pen_down);
  // Both times read back exactly from the metadata.
  EXPECT_EQ(std::stod(extra.at("writing_begin_s")), r.writing_begin_s);
  EXPECT_EQ(std::stod(extra.at("writing_end_s")), r.writing_end_s);
  // The same samples end the trial at the same tick.
  device::ProfileHandScript again(writeThenLift(1.0, 1.2));
  EXPECT_EQ(runTrial(env, setup, again).profile.size(), r.profile.size());
}

TEST(TrialEnd, AHandThatNeverLiftsEndsAtTheMaximum) {
  TrialEnvironment env("sim://pen", flatWorld(), 1000.0);
  device::ProfileHandScript hand(writeThenLift(5.0, 5.0));  // still writing at the maximum
  const TrialResult r = runTrial(env, TrialSetup{.duration_s = 1.0, .pen_up_end_s = 0.3}, hand);
  EXPECT_EQ(r.end_reason, "maximum duration");
  EXPECT_EQ(r.profile.metadata().extra.at("end_reason"), "maximum duration");
  EXPECT_EQ(r.profile.size(), 1000u);
  // The pen was still down: writing ends with the last sample.
  EXPECT_EQ(r.writing_end_s, r.profile.samples().back().t_s);
}

// The studio's expert takes: recording from the first pen-down, stopped by a pen-up as long as
// the end rule's. The trigger's stop is where writing ends; the trial says "pen lifted".
TEST(TrialEnd, APenDownTriggerWithTheSamePenUpTimeEndsAsPenLifted) {
  TrialEnvironment env("sim://pen", flatWorld(), 1000.0);
  device::ProfileHandScript hand(writeThenLift(1.0, 1.2));
  TrialSetup setup{.duration_s = 10.0, .pen_up_end_s = 0.5, .trigger = RecordTrigger::kPenDown};
  const TrialResult r = runTrial(env, setup, hand);
  EXPECT_EQ(r.end_reason, "pen lifted");
  EXPECT_GT(r.writing_end_s, 0.8);
  EXPECT_LT(r.profile.samples().back().t_s, 2.0);  // not the 10 s maximum
}

TEST(TrialEnd, WithoutTheRuleATrialLastsItsWholeDuration) {
  HATTR_STARTS_NO_THREAD();
  TrialEnvironment env("sim://pen", flatWorld(), 1000.0);
  device::ProfileHandScript hand(writeThenLift(0.5, 0.6));
  const TrialResult r = runTrial(env, TrialSetup{.duration_s = 1.5}, hand);
  EXPECT_EQ(r.end_reason, "maximum duration");
  EXPECT_EQ(r.profile.size(), 1500u);
}

TEST(TrialEnd, ARealTimeTrialEndsWhenStopped) {
  TrialEnvironment env("sim://pen", flatWorld(), 1000.0);
  test::passesUnlessTheHostStalls([&](std::uint64_t& host_stalls) {
    device::ProfileHandScript hand(writeThenLift(30.0, 30.0));  // never lifts
    TrialStop stop;
    TrialSetup setup{.duration_s = 30.0, .pen_up_end_s = 1.0, .stop = &stop};
    setup.clock = Clock::kRealTime;
    std::thread stopper([&stop] {
      std::this_thread::sleep_for(std::chrono::milliseconds(800));  // settle 0.3 s, then writing
      stop.request();
    });
    const auto start = std::chrono::steady_clock::now();
    const TrialResult r = runTrial(env, setup, hand);
    stopper.join();
    host_stalls = r.stalls;
    const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!r.failure.empty()) {
      ADD_FAILURE() << "failed: " << r.failure;
      return;
    }
    EXPECT_EQ(r.end_reason, "stopped");
    EXPECT_EQ(r.profile.metadata().extra.at("end_reason"), "stopped");
    EXPECT_LT(took_s, 10.0);  // far from the 30 s maximum
  });
}

TEST(TrialEnd, ARealTimeTrialRecordsTheWindowOfLoopTimeFromTheSettlesEndToTheTrials) {
  // The recording is the loop-time window [0.3 s, 0.9 s), up to the lateness of the ticks at
  // its edges: not whatever the trial's own thread, waking every 2 ms, saw between them.
  TrialEnvironment env("sim://pen", flatWorld(), 1000.0);
  test::passesUnlessTheHostStalls([&](std::uint64_t& host_stalls) {
    device::ProfileHandScript hand(writeThenLift(0.4, 0.5));
    TrialSetup setup{.duration_s = 0.6};
    setup.clock = Clock::kRealTime;
    const TrialResult r = runTrial(env, setup, hand);
    host_stalls = r.stalls;
    ASSERT_EQ(r.failure, "");
    EXPECT_EQ(r.end_reason, "maximum duration");
    EXPECT_EQ(r.missed_samples, 0u);
    const double late_s = r.max_period_error_s + 0.5e-3;  // a tick's lateness, and half a period
    const double first_s = std::stod(r.profile.metadata().extra.at("t_origin_s"));
    const double last_s = first_s + r.profile.samples().back().t_s;
    EXPECT_GE(first_s, 0.3 - 0.5e-3);
    EXPECT_LE(first_s, 0.3 + late_s) << "max period error " << r.max_period_error_s;
    EXPECT_LT(last_s, 0.9 - 0.5e-3);
    EXPECT_GE(last_s, 0.9 - 1e-3 - late_s) << "max period error " << r.max_period_error_s;
  });
}

TEST(TrialEnd, RefusesABadPenUpTime) {
  TrialEnvironment env("sim://pen", flatWorld(), 1000.0);
  device::ProfileHandScript hand(writeThenLift(0.5, 0.6));
  try {
    (void)runTrial(env, TrialSetup{.duration_s = 1.0, .pen_up_end_s = -1.0}, hand);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("trial end: pen-up time: expected [0, 60] s (0: off), got -1"));
  }
}

std::string studyError(const std::string& protocol) {
  const std::string json = R"({"name": "x", "skill": "na", "experts": {"na": "e.csv"}, "protocol": )" + protocol +
                           R"(, "subjects": {"count": 1}})";
  try {
    (void)parseStudy(json, "study.json", ".", false);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(StudyTrialEnd, DefaultsToAOneSecondPenUpAndThreeTimesTheExpert) {
  const StudyDefinition s =
      parseStudy(R"({"name": "x", "skill": "na", "experts": {"na": "e.csv"}, "subjects": {"count": 1}})", "s.json",
                 ".", false);
  EXPECT_FALSE(s.protocol.fixed_window);
  EXPECT_EQ(s.protocol.trial_end.pen_up_s, 1.0);
  EXPECT_EQ(s.protocol.trial_end.maxDuration_s(4.0), 12.0);
  // Read back from the stored definition unchanged.
  const StudyDefinition back = parseStudy(studyToJson(s).dump(), "db", ".", false);
  EXPECT_FALSE(back.protocol.fixed_window);
  EXPECT_EQ(back.protocol.trial_end.pen_up_s, 1.0);
}

TEST(StudyTrialEnd, AnOldFileWithTailKeepsItsFixedWindow) {
  const StudyDefinition s = parseStudy(
      R"({"name": "x", "skill": "na", "experts": {"na": "e.csv"}, "protocol": {"tail_s": 0.2}, "subjects": {"count": 1}})",
      "s.json", ".", false);
  EXPECT_TRUE(s.protocol.fixed_window);
  EXPECT_TRUE(parseStudy(studyToJson(s).dump(), "db", ".", false).protocol.fixed_window);
}

TEST(StudyTrialEnd, ValidationSaysWhatIsWrong) {
  EXPECT_THAT(studyError(R"({"trial_end": {"pen_up_s": 0}})"),
              HasSubstr("protocol.trial_end.pen_up_s: expected a number in [0.05, 60], got 0"));
  EXPECT_THAT(studyError(R"({"trial_end": {"max_s": "long"}})"),
              HasSubstr("protocol.trial_end.max_s: expected a number in [0, 3600], got \"long\""));
  EXPECT_THAT(studyError(R"({"trial_end": {"pen_up_s": 2, "max_s": 1}})"),
              HasSubstr("protocol.trial_end.max_s: expected 0 (3 × the expert's duration) or more than pen_up_s = 2, got 1"));
  EXPECT_THAT(studyError(R"({"trial_end": {"pen_up": 1}})"),
              HasSubstr("protocol.trial_end: unknown key \"pen_up\": expected pen_up_s, max_s"));
  EXPECT_THAT(studyError(R"({"trial_end": 3})"), HasSubstr("protocol.trial_end: expected an object"));
}

}  // namespace
}  // namespace hattr::session
