// The live rig (the studio's runTrial that stays open) and the study stepper (the studio's
// StudyRunner for a person): the same library calls, the same bits.
#include <QtTest>
#include <sqlite3.h>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <thread>

#include "core/live_rig.hpp"
#include "core/mouse_hand.hpp"
#include "core/study_report_export.hpp"
#include "core/study_session.hpp"
#include "hattr/core/error.hpp"
#include "hattr/wire/packet.hpp"
#include "hattr/wire/udp_socket.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/net/study_mentor.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/study_runner.hpp"
#include "studio_test_support.hpp"

using namespace hattr;
using namespace hattr::studio;

namespace {

/// Equal in everything but the creation time; on a difference, says where.
bool sameButCreationTime(HapticProfile a, HapticProfile b) {
  a.metadata().created_utc.clear();
  b.metadata().created_utc.clear();
  if (!(a.metadata() == b.metadata())) {
    for (const auto& [k, v] : a.metadata().extra) {
      if (b.metadata().extra[k] != v)
        qWarning("metadata %s: %s vs %s", k.c_str(), v.c_str(), b.metadata().extra[k].c_str());
    }
    qWarning("subject %s/%s source %s/%s device %s/%s rate %g/%g", a.metadata().subject.c_str(),
             b.metadata().subject.c_str(), a.metadata().source.c_str(), b.metadata().source.c_str(),
             a.metadata().device.c_str(), b.metadata().device.c_str(), a.metadata().nominal_rate_hz,
             b.metadata().nominal_rate_hz);
  }
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (!(a[i] == b[i])) {
      qWarning("sample %zu differs: t %.17g/%.17g x %.17g/%.17g fz %.17g/%.17g", i, a[i].t_s, b[i].t_s, a[i].p_WT.x(),
               b[i].p_WT.x(), a[i].f_user_W.z(), b[i].f_user_W.z());
      break;
    }
  }
  return a == b;
}

/// The end rule of the studies below (an old file's fixed window is smallStudyJson's default).
const char* const kPenUpEnd = "\"trial_end\": {\"pen_up_s\": 0.4, \"max_s\": 0}";

/// The studio's test study; `trial_end` as smallStudyJson's; P01's scripted hand (when the
/// runner plays P01) is `hand_file`, or the expert when empty.
std::string studyJson(const std::string& trial_end = "\"tail_s\": 0.2", const std::string& hand_file = "") {
  const std::string options = hand_file.empty() ? "" : ", \"options\": {\"hand\": \"" + hand_file + "\"}";
  return test::smallStudyJson("[\"basic\", \"pcontrol\"]", 2.0,
                              "[{\"id\": \"P01\", \"participant\": \"person\"" + options +
                                  "}, "
                                  "{\"id\": \"S01\", \"participant\": \"script\", \"seed\": 3}]",
                              "flat", trial_end);
}

}  // namespace

class StudioRigTest : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    environment_ = std::make_unique<session::TrialEnvironment>("sim://pen", test::flatWorld(), 1000.0);
    expert_ = test::recordExpert(*environment_);
    QVERIFY(expert_.size() > 1000);
    reference_ = std::make_shared<guidance::ReferenceTrajectory>(expert_, 1000.0);
  }

  // ---- LiveRig ----
  void liveRigRecordsWhatRunTrialRecordsBitForBit_data() {
    QTest::addColumn<bool>("end_rule");
    QTest::newRow("fixed window") << false;
    QTest::newRow("pen-up end rule") << true;
  }

  // Without an end rule the trial lasts its duration; with one, the hand lifts the pen after
  // writing and the trial ends pen_up_end_s later, at the same sample and tick in both.
  void liveRigRecordsWhatRunTrialRecordsBitForBit() {
    QFETCH(bool, end_rule);
    const HapticProfile script = end_rule ? test::writeThenLift(expert_, 1.0) : expert_;
    for (const auto mode : {guidance::TrainingMode::kBasic, guidance::TrainingMode::kPositionControl,
                            guidance::TrainingMode::kForceControl}) {
      session::TrialSetup setup;
      setup.guidance.mode = mode;
      setup.reference = reference_;
      setup.duration_s = reference_->duration_s() + (end_rule ? 3.0 : 0.3);
      setup.pen_up_end_s = end_rule ? 0.4 : 0.0;
      setup.metadata.subject = "T1";
      setup.metadata.skill = "eight";
      device::ProfileHandScript hand_a(script, 1.0471975511965976, Vec3(0.002, -0.001, 0.0));
      const session::TrialResult a = session::runTrial(*environment_, setup, hand_a);
      QCOMPARE(a.end_reason, std::string(end_rule ? session::kEndPenLifted : session::kEndMaximumDuration));

      device::ProfileHandScript hand_b(script, 1.0471975511965976, Vec3(0.002, -0.001, 0.0));
      LiveRig rig;
      const RunSpec spec = trialRunSpec(setup, false);
      QCOMPARE(spec.pen_up_end_s, setup.pen_up_end_s);
      rig.start(*environment_, spec, hand_b, session::Clock::kSimulated);
      rig.advanceSimulated(setup.settle_s);
      rig.advanceSimulated(setup.duration_s);
      QVERIFY(rig.status().window_done);
      QCOMPARE(rig.status().writing_over, end_rule);
      const session::TrialResult b = rig.finish();
      QVERIFY(!rig.active());
      QCOMPARE(b.profile.size(), a.profile.size());
      QVERIFY2(sameButCreationTime(a.profile, b.profile), guidance::modeName(mode).data());
      QCOMPARE(b.end_reason, a.end_reason);
      QCOMPARE(b.profile.metadata().extra.at("end_reason"), a.end_reason);
      QCOMPARE(b.writing_begin_s, a.writing_begin_s);
      QCOMPARE(b.writing_end_s, a.writing_end_s);
      // The loop stopped with the same chunk (a study stores the tick count).
      QCOMPARE(b.ticks, a.ticks);
      QCOMPARE(b.clamps, a.clamps);
      QCOMPARE(b.missed_samples, std::uint64_t{0});
    }
  }

  // The stop key: a real-time trial (an end rule, a 30 s maximum, the pen held down) ends
  // when asked, "stopped", with nothing recorded after the request.
  void liveRigStopRequestEndsARealTimeRunAsStopped() {
    const test::RealTimeOutcome outcome = test::passesUnlessTheHostStalls([this](std::uint64_t& host_stalls) {
      MouseHand hand;
      hand.setInput({.x_m = 0.0, .y_m = 0.0, .pen_down = false, .press_N = 1.2});
      RunSpec spec;
      spec.record = RecordMode::kWindow;
      spec.settle_s = 0.3;
      spec.duration_s = 30.0;
      spec.pen_up_end_s = 1.0;
      LiveRig rig;
      rig.start(*environment_, spec, hand, session::Clock::kRealTime);
      const auto begin = std::chrono::steady_clock::now();
      const auto elapsed_s = [&begin] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
      };
      Sample latest;
      // Write until 0.3 s of the trial are recorded.
      while (rig.status().recorded_samples < 300 && elapsed_s() < 10.0) {
        hand.setInput({.x_m = 0.01 * elapsed_s(), .y_m = 0.0, .pen_down = true, .press_N = 1.2});
        (void)rig.readLatest(latest);
        std::this_thread::sleep_for(std::chrono::milliseconds(16));
      }
      rig.requestStop();
      (void)rig.readLatest(latest);  // the newest sample the loop had published at the request
      const double requested_at_s = latest.t_s;
      // The loop runs on (the pen still down); the recording does not.
      const auto asked = std::chrono::steady_clock::now();
      while (!rig.status().stopped && std::chrono::steady_clock::now() - asked < std::chrono::seconds(2)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      const bool stopped_status = rig.status().stopped;
      const bool window_done = rig.status().window_done;
      const session::TrialResult r = rig.finish();
      host_stalls = r.stalls;
      std::string failures;
      const auto check = [&failures](bool ok, const std::string& what) {
        if (!ok) failures += what + "; ";
      };
      check(stopped_status, "the rig's status does not say stopped");
      check(!window_done, "the window ended by itself");
      check(r.end_reason == session::kEndStopped, "end_reason: expected stopped, got " + r.end_reason);
      check(!r.profile.empty() && r.profile.metadata().extra.at("end_reason") == "stopped",
            "the profile's metadata end_reason is not stopped");
      check(r.profile.size() >= 300, "recorded " + std::to_string(r.profile.size()) + " samples, expected >= 300");
      if (!r.profile.empty()) {
        const double last_s = r.profile.samples().back().t_s + std::stod(r.profile.metadata().extra.at("t_origin_s"));
        check(last_s <= requested_at_s + 0.002, "recorded until loop time " + std::to_string(last_s) +
                                                    " s, after the request at " + std::to_string(requested_at_s) +
                                                    " s");
      }
      check(r.writing_begin_s >= 0.0, "no writing recorded");
      return failures;
    });
    if (outcome.every_attempt_stalled) QSKIP(("the host stalled every attempt: " + outcome.failures).c_str());
    QVERIFY2(outcome.passed, outcome.failures.c_str());
  }

  // A device fault ends a studio trial as it ends runTrial's: at the fault, with the device's
  // reason, marked failed, what came before kept and nothing after it.
  void liveRigEndsATrialAtADeviceFaultAsRunTrialDoes() {
    // The fake vendor's plugin, named by ctest (tests/studio/CMakeLists.txt).
    const char* plugin = std::getenv("HATTR_FAKE_VENDOR_PLUGIN");
    QVERIFY2(plugin != nullptr, "HATTR_FAKE_VENDOR_PLUGIN is not set: run this test through ctest");
    session::TrialEnvironment env(std::string("plugin:") + plugin + "?clock=device&error_after=500",
                                  render::WorldConfig{}, 1000.0);
    MouseHand hand;
    hand.setInput({.x_m = 0.0, .y_m = 0.0, .pen_down = false, .press_N = 1.2});
    const session::TrialSetup setup{.duration_s = 2.0, .settle_s = 0.3};
    const test::RealTimeOutcome outcome = test::passesUnlessTheHostStalls([&](std::uint64_t& host_stalls) {
      const session::TrialResult expected = session::runTrial(env, setup, hand);
      LiveRig rig;
      rig.start(env, trialRunSpec(setup, false), hand, session::Clock::kRealTime);
      const auto begin = std::chrono::steady_clock::now();
      while (!rig.status().failed && std::chrono::steady_clock::now() - begin < std::chrono::seconds(3)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      const bool failed_status = rig.status().failed;
      const bool window_done = rig.status().window_done;
      const session::TrialResult r = rig.finish();
      host_stalls = r.stalls + expected.stalls;
      std::string failures;
      const auto check = [&failures](bool ok, const std::string& what) {
        if (!ok) failures += what + "; ";
      };
      check(expected.failure.find("fake SDK: amplifier fault") != std::string::npos,
            "runTrial's failure: " + expected.failure);
      check(failed_status && window_done, "the rig's status does not say failed and done");
      check(r.failure == expected.failure, "failure: \"" + r.failure + "\", runTrial's \"" + expected.failure + "\"");
      check(r.end_reason == session::kEndFailed, "end_reason: expected failed, got " + r.end_reason);
      check(r.ticks < 1000, "the loop ran " + std::to_string(r.ticks) + " ticks, past the fault at 500");
      check(r.profile.size() > 100, "recorded " + std::to_string(r.profile.size()) + " samples before the fault");
      if (!r.profile.empty()) {
        check(r.profile.metadata().extra.count("failed") == 1 && r.profile.metadata().extra.at("failed") == r.failure,
              "the profile is not marked failed with the reason");
        // The same pipeline's metadata: the device's own clock is named as runTrial names it.
        const auto clock_of = [](const session::TrialResult& t) {
          const auto it = t.profile.metadata().extra.find("clock");
          return it == t.profile.metadata().extra.end() ? std::string("(none)") : it->second;
        };
        check(clock_of(r) == "device" && clock_of(expected) == "device",
              "clock: the rig's \"" + clock_of(r) + "\", runTrial's \"" + clock_of(expected) + "\"");
        // From the fault on the loop commanded zero; the faulting tick is the last one kept.
        check(r.profile.samples().back().f_cmd_W.norm() == 0.0, "the last recorded command is not zero");
        check(r.profile.size() <= expected.profile.size() + 5,
              "recorded " + std::to_string(r.profile.size()) + " samples, runTrial " +
                  std::to_string(expected.profile.size()) + ": more than the ticks up to the fault");
      }
      return failures;
    });
    if (outcome.every_attempt_stalled) QSKIP(("the host stalled every attempt: " + outcome.failures).c_str());
    QVERIFY2(outcome.passed, outcome.failures.c_str());
  }

  void liveRigRefusesABadPenUpTimeSayingWhy() {
    MouseHand hand;
    LiveRig rig;
    RunSpec spec;
    spec.pen_up_end_s = -1.0;
    try {
      rig.start(*environment_, spec, hand, session::Clock::kSimulated);
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("trial end: pen-up time: expected [0, 60] s (0: off), got -1"), e.what());
    }
    QVERIFY(!rig.active());
  }

  void liveRigSwitchesModeThroughTheMailbox() {
    MouseHand hand;
    hand.setInput({.x_m = 0.008, .y_m = 0.0, .pen_down = false, .press_N = 1.0});
    RunSpec spec;
    spec.reference = reference_;
    spec.guidance.mode = guidance::TrainingMode::kBasic;
    LiveRig rig;
    rig.start(*environment_, spec, hand, session::Clock::kSimulated);
    rig.advanceSimulated(0.5);
    Sample s;
    QVERIFY(rig.readLatest(s));
    QCOMPARE(s.f_guide_W.norm(), 0.0);
    QVERIFY(rig.switchMode(guidance::TrainingMode::kPositionControl));
    rig.advanceSimulated(0.2);
    QVERIFY(rig.readLatest(s));
    QVERIFY2(s.f_guide_W.norm() > 0.1, "PCONTROL pulls the pen toward the reference");
    (void)rig.finish();
  }

  // The reference marker is where the guidance plays the reference: nothing during the settle;
  // with time indexing, the point 0.5 s into the reference after 0.5 s of the trial; with
  // progress indexing, the reference's point under a pen held over it (its index 150).
  void liveRigCueIsWhereTheGuidancePlaysTheReference() {
    const Vec3 over = reference_->at(150.0).p_WT;
    const auto cueAfter = [&](guidance::Indexing indexing) {
      MouseHand hand;
      hand.setInput({.x_m = over.x(), .y_m = over.y(), .pen_down = false, .press_N = 1.0});
      RunSpec spec;
      spec.reference = reference_;
      spec.guidance.mode = guidance::TrainingMode::kBasic;
      spec.guidance.playback.indexing = indexing;
      spec.settle_s = 0.3;
      LiveRig rig;
      rig.start(*environment_, spec, hand, session::Clock::kSimulated);
      rig.advanceSimulated(0.2);
      const bool none_while_settling = !rig.referenceCue().has_value();
      rig.advanceSimulated(0.6);
      const std::optional<Vec3> cue = rig.referenceCue();
      (void)rig.finish();
      return std::make_pair(none_while_settling, cue);
    };
    const auto [time_settling, time_cue] = cueAfter(guidance::Indexing::kTime);
    QVERIFY(time_settling);
    QVERIFY(time_cue.has_value());
    // 0.5 s into the trial at 1 kHz: index 500 (the chunk may end a few ticks later).
    double nearest = 1e9;
    for (int i = 495; i <= 520; ++i) nearest = std::min(nearest, (*time_cue - reference_->at(i).p_WT).norm());
    QVERIFY2(nearest < 1e-12, qPrintable(QString("the cue is %1 m from the reference's points 495..520").arg(nearest)));
    const auto [progress_settling, progress_cue] = cueAfter(guidance::Indexing::kProgress);
    QVERIFY(progress_settling);
    QVERIFY(progress_cue.has_value());
    const double under_pen = (progress_cue->head<2>() - over.head<2>()).norm();
    QVERIFY2(under_pen < 0.001, qPrintable(QString("the progress cue is %1 m from the point under the pen").arg(under_pen)));
    QVERIFY((*progress_cue - *time_cue).norm() > 0.005);  // the two indexings differ here
  }

  void liveRigPenDownTriggerRecordsFromTouchUntilALongLift() {
    MouseHand hand;
    hand.setInput({.x_m = 0.0, .y_m = 0.0, .pen_down = false, .press_N = 1.2});
    RunSpec spec;
    spec.record = RecordMode::kPenDown;
    spec.pen_up_stop_s = 0.2;
    LiveRig rig;
    rig.start(*environment_, spec, hand, session::Clock::kSimulated);
    rig.advanceSimulated(0.5);
    QVERIFY(!rig.status().recording);
    QCOMPARE(rig.status().recorded_samples, std::uint64_t{0});
    hand.setInput({.x_m = 0.01, .y_m = 0.0, .pen_down = true, .press_N = 1.2});
    rig.advanceSimulated(0.5);
    QVERIFY(rig.status().recording);
    hand.setInput({.x_m = 0.01, .y_m = 0.0, .pen_down = false, .press_N = 1.2});
    rig.advanceSimulated(0.5);
    QVERIFY(rig.status().pen_down_done);
    const session::TrialResult r = rig.finish();
    QVERIFY(r.profile.size() > 300);
    QVERIFY(r.profile[0].pen_down);
    QVERIFY(!r.profile.samples().back().pen_down);
  }

  void liveRigInRealTimeRecordsTheTrialWindowAsTheMouseMoves() {
    MouseHand hand;
    hand.setInput({.x_m = 0.0, .y_m = 0.0, .pen_down = false, .press_N = 1.2});
    RunSpec spec;
    spec.record = RecordMode::kWindow;
    spec.settle_s = 0.3;
    spec.duration_s = 0.4;
    LiveRig rig;
    rig.start(*environment_, spec, hand, session::Clock::kRealTime);
    const auto begin = std::chrono::steady_clock::now();
    Sample latest;
    // The GUI thread's part: move the mouse with the button held, read the newest sample.
    while (!rig.status().window_done && std::chrono::steady_clock::now() - begin < std::chrono::seconds(5)) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
      hand.setInput({.x_m = 0.02 * t, .y_m = 0.0, .pen_down = true, .press_N = 1.2});
      (void)rig.readLatest(latest);
      std::this_thread::sleep_for(std::chrono::milliseconds(16));
    }
    QVERIFY(rig.status().window_done);
    const session::TrialResult r = rig.finish();
    QVERIFY(r.ticks > 100);
    // The trial's window on its own clock: from 0 to under 0.4 s, at most one sample per
    // tick (how many depends on the machine's timing, which decides nothing here).
    QVERIFY2(r.profile.size() > 50 && r.profile.size() <= 401, std::to_string(r.profile.size()).c_str());
    QCOMPARE(r.profile[0].t_s, 0.0);
    QVERIFY(r.profile.samples().back().t_s > 0.2 && r.profile.samples().back().t_s < 0.4);
    const double origin = std::stod(r.profile.metadata().extra.at("t_origin_s"));
    QVERIFY(origin >= 0.2995 && origin < 0.31);
    QCOMPARE(r.profile.metadata().extra.at("clock"), std::string("real-time"));
    QVERIFY(r.profile.penDownCount() > 0);
  }

  void liveRigRestartsCleanlyWhileRunning() {
    MouseHand hand;
    LiveRig rig;
    RunSpec spec;
    rig.start(*environment_, spec, hand, session::Clock::kRealTime);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    rig.start(*environment_, spec, hand, session::Clock::kRealTime);  // finishes the first run
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    QVERIFY(rig.status().running);
    QVERIFY(rig.counters()->ticks.load() > 10);
    const session::TrialResult r = rig.finish();
    QVERIFY(r.profile.empty());  // nothing recorded
    QVERIFY(!rig.active());
    QVERIFY(!rig.status().running);
  }

  void liveRigRefusesATooShortSettleSayingWhy() {
    MouseHand hand;
    LiveRig rig;
    RunSpec spec;
    spec.settle_s = 0.1;
    try {
      rig.start(*environment_, spec, hand, session::Clock::kSimulated);
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("settle time: expected [0.25, 60] s"), e.what());
    }
    QVERIFY(!rig.active());
  }

  // ---- StudySession ----
  void studySessionStoresWhatTheStudyRunnerStoresBitForBit_data() {
    QTest::addColumn<bool>("end_rule");
    QTest::newRow("fixed window (old file)") << false;
    QTest::newRow("trial_end") << true;
  }

  // With trial_end, P01's hand lifts the pen after writing: every trial ends by the end rule,
  // at the same sample and tick in both (the loop's tick count is stored).
  void studySessionStoresWhatTheStudyRunnerStoresBitForBit() {
    QFETCH(bool, end_rule);
    const auto dir = makeStudyFolder(end_rule ? "same-end" : "same");
    const auto hand_file = dir / "lift.csv";
    const HapticProfile lift = test::writeThenLift(expert_, 1.0);
    io::writeProfileCsv(lift, hand_file);
    if (end_rule) std::ofstream(dir / "study.json") << studyJson(kPenUpEnd, hand_file.string());
    const session::StudyDefinition study = session::loadStudy(dir / "study.json");
    QCOMPARE(study.protocol.fixed_window, !end_rule);
    { (void)session::StudyDatabase::create(dir / "runner.sqlite", study); }
    { (void)session::StudyDatabase::create(dir / "studio.sqlite", study); }

    // The CLI's way: the runner with a scripted participant.
    {
      auto db = session::StudyDatabase::open(dir / "runner.sqlite", session::OpenMode::kRunner);
      session::StudyRunner runner(db, session::makeScriptParticipant);
      QCOMPARE(runner.run({.only_subject = "P01"}), 4);
    }
    // The studio's way: the stepper and the live rig, with the same hand in simulated time.
    {
      StudySession session(dir / "studio.sqlite");
      session.selectSubject("P01", 0.0);
      QCOMPARE(session.state(), StudySession::State::kReady);
      double now = 0.0;
      LiveRig rig;
      while (session.state() != StudySession::State::kFinished) {
        session.tick(now);
        if (session.state() == StudySession::State::kResting) {
          now += 1.0;
          continue;
        }
        QCOMPARE(session.state(), StudySession::State::kReady);
        const session::TrialSetup setup = session.currentSetup();
        session.beginTrial();
        const HapticProfile script = end_rule ? io::readProfileCsv(hand_file) : session.expert();
        device::ProfileHandScript hand(script, 1.0471975511965976, Vec3(0.0, 0.0, 0.0));
        rig.start(session.environment(), trialRunSpec(setup, false), hand, session::Clock::kSimulated);
        rig.advanceSimulated(setup.settle_s);
        rig.advanceSimulated(setup.duration_s);
        session.completeTrial(rig.finish(), now);
      }
      QCOMPARE(session.completedCount(), 4);
    }
    const auto a = session::StudyDatabase::open(dir / "runner.sqlite", session::OpenMode::kReadOnly);
    const auto b = session::StudyDatabase::open(dir / "studio.sqlite", session::OpenMode::kReadOnly);
    const auto ta = a.trials("P01");
    const auto tb = b.trials("P01");
    QCOMPARE(tb.size(), ta.size());
    for (std::size_t i = 0; i < ta.size(); ++i) {
      QCOMPARE(tb[i].status, session::TrialStatus::kCompleted);
      QCOMPARE(tb[i].outcome, ta[i].outcome);
      const HapticProfile pa = a.trialProfile(ta[i].id);
      const HapticProfile pb = b.trialProfile(tb[i].id);
      QCOMPARE(pa.metadata().extra.at("end_reason"),
               std::string(end_rule ? session::kEndPenLifted : session::kEndMaximumDuration));
      QVERIFY2(sameButCreationTime(pa, pb), std::to_string(i).c_str());
      QVERIFY2(pa == pb, std::to_string(i).c_str());
    }
    std::filesystem::remove_all(dir);
  }

  // The studio's set-up of a study trial is the runner's (session::studyTrialSetup), on the
  // real-time clock: the end rule and its maximum, or an old file's fixed window.
  void studySessionSetsUpEachTrialAsTheRunnerDoes_data() {
    QTest::addColumn<bool>("end_rule");
    QTest::newRow("fixed window (old file)") << false;
    QTest::newRow("trial_end") << true;
  }

  void studySessionSetsUpEachTrialAsTheRunnerDoes() {
    QFETCH(bool, end_rule);
    const auto dir = makeStudyFolder(end_rule ? "setup-end" : "setup");
    if (end_rule) std::ofstream(dir / "study.json") << studyJson(kPenUpEnd);
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    {
      StudySession session(dir / "s.sqlite");
      session.selectSubject("P01", 0.0);
      const double expert_s = session.reference()->duration_s();
      int trials = 0;
      while (session.state() != StudySession::State::kFinished) {
        session.skipRest();
        const session::TrialPlan plan = session.currentTrial()->plan;
        const session::TrialSetup got = session.currentSetup();
        const session::TrialSetup want = session::studyTrialSetup(session.study(), plan, session.reference());
        // What the runner runs; what the study file says.
        QCOMPARE(got.duration_s, want.duration_s);
        QCOMPARE(got.pen_up_end_s, want.pen_up_end_s);
        QCOMPARE(got.duration_s, end_rule ? 3.0 * expert_s : expert_s + 0.2);
        QCOMPARE(got.pen_up_end_s, end_rule ? 0.4 : 0.0);
        QCOMPARE(got.guidance.mode, want.guidance.mode);
        QCOMPARE(got.guidance.mode, plan.view.guidance ? plan.mode : guidance::TrainingMode::kBasic);
        QCOMPARE(got.guidance.playback.indexing, want.guidance.playback.indexing);
        QVERIFY(got.reference == session.reference());
        QVERIFY(got.metadata == want.metadata);
        QCOMPARE(got.metadata.subject, std::string("P01"));
        QCOMPARE(got.metadata.extra.at("phase"), plan.phase);
        QCOMPARE(got.settle_s, want.settle_s);
        QVERIFY(got.trigger == want.trigger);
        QVERIFY(got.stop == nullptr);
        QVERIFY(got.clock == session::Clock::kRealTime);
        // The rig's run of it carries the end rule.
        QCOMPARE(trialRunSpec(got, true).pen_up_end_s, got.pen_up_end_s);
        QCOMPARE(trialRunSpec(got, true).duration_s, got.duration_s);
        runOneTrial(session, 0.0);
        ++trials;
      }
      QCOMPARE(trials, 4);
    }
    std::filesystem::remove_all(dir);
  }

  void studyTrialSetupRefusesAMissingReference() {
    const auto dir = makeStudyFolder("noref");
    const session::StudyDefinition study = session::loadStudy(dir / "study.json");
    const session::TrialPlan plan{.subject = "P01", .sequence = 2};
    try {
      (void)session::studyTrialSetup(study, plan, nullptr);
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains(
                   "study \"studio test\", subject P01, trial 2: expected the expert's reference trajectory, got none"),
               e.what());
    }
    std::filesystem::remove_all(dir);
  }

  void studySessionRestsPromptsAndResumes() {
    const auto dir = makeStudyFolder("resume");
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    {
      StudySession session(dir / "s.sqlite");
      QCOMPARE(session.participantKind(), std::string());
      session.selectSubject("P01", 100.0);
      QCOMPARE(session.participantKind(), std::string("person"));
      QCOMPARE(session.prompt(), std::string("Training with BASIC: trial 1 of 1"));
      QCOMPARE(session.currentSetup().guidance.mode, guidance::TrainingMode::kBasic);
      runOneTrial(session, 100.0);
      // A rest of rest_s before the next trial, then ready.
      QCOMPARE(session.state(), StudySession::State::kResting);
      QCOMPARE(session.restRemaining_s(101.0), 1.0);
      session.tick(101.5);
      QCOMPARE(session.state(), StudySession::State::kResting);
      session.tick(102.0);
      QCOMPARE(session.state(), StudySession::State::kReady);
      QCOMPARE(session.prompt(), std::string("Recall with BASIC: trial 1 of 1"));
      QVERIFY(!session.currentTrial()->plan.view.show_reference);
    }
    {
      // Reopened: resumes at trial 2, after a rest (the runner's rule).
      StudySession session(dir / "s.sqlite");
      session.selectSubject("P01", 0.0);
      QCOMPARE(session.completedCount(), 1);
      QCOMPARE(session.state(), StudySession::State::kResting);
      session.skipRest();
      QCOMPARE(session.state(), StudySession::State::kReady);
      QCOMPARE(session.currentTrial()->plan.sequence, 1);
    }
    std::filesystem::remove_all(dir);
  }

  // A design's sessions on other days: at a session's end the next waits to be begun, early
  // here (it is due tomorrow), and a reopened study offers it again; begun, it runs.
  void studySessionOffersTheNextSessionWithItsDueDate() {
    const auto dir = makeStudyFolder("sessions");
    std::ofstream(dir / "study.json") << test::designStudyJson(1.0);
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    const std::string tomorrow = session::addDays(session::localToday(), 1).iso();
    {
      StudySession session(dir / "s.sqlite");
      session.selectSubject("P01", 0.0);
      QCOMPARE(session.state(), StudySession::State::kReady);
      QCOMPARE(session.prompt(), std::string("Training with PCONTROL: trial 1 of 1"));
      // The plain wording (the studio's default view): the strategy's plain name.
      QCOMPARE(session.prompt(session::SubjectTrials::Wording::kPlain), std::string("Training with Guided path: trial 1 of 1"));
      QCOMPARE(session.currentSetup().guidance.mode, guidance::TrainingMode::kPositionControl);
      runOneTrial(session, 0.0);
      QCOMPARE(session.state(), StudySession::State::kResting);
      session.skipRest();
      QCOMPARE(session.prompt(), std::string("Post-test: trial 1 of 1"));
      QCOMPARE(session.prompt(session::SubjectTrials::Wording::kPlain), std::string("Written alone: trial 1 of 1"));
      QCOMPARE(session.currentSetup().guidance.mode, guidance::TrainingMode::kBasic);
      runOneTrial(session, 10.0);
      QCOMPARE(session.state(), StudySession::State::kNextSession);
      QCOMPARE(session.schedule().timing, session::SubjectSchedule::Timing::kEarly);
      QCOMPARE(session.prompt(), "Next session for P01: session 2 of 2 (day 1), due on " + tomorrow + " (in 1 day): early");
    }
    {
      StudySession session(dir / "s.sqlite");
      session.selectSubject("P01", 0.0);
      QCOMPARE(session.state(), StudySession::State::kNextSession);  // reopened between sessions
      session.beginNextSession();
      QCOMPARE(session.state(), StudySession::State::kReady);
      QCOMPARE(session.prompt(), std::string("Retention: trial 1 of 1"));
      QCOMPARE(session.prompt(session::SubjectTrials::Wording::kPlain),
               std::string("Written alone, days later: trial 1 of 1"));
      QVERIFY(!session.currentTrial()->plan.view.show_reference);
      runOneTrial(session, 0.0);
      QCOMPARE(session.state(), StudySession::State::kFinished);
      QCOMPARE(session.schedule().timing, session::SubjectSchedule::Timing::kDone);
    }
    // Review's report of a design is the design's.
    {
      const auto db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kReadOnly);
      const ReviewReport report = writeReviewReport(db, dir / "s.sqlite");
      QCOMPARE(report.costs.size(), std::size_t{3});
      std::ifstream page(report.html);
      const std::string html((std::istreambuf_iterator<char>(page)), std::istreambuf_iterator<char>());
      QVERIFY(html.find("Learning curves") != std::string::npos);
      QVERIFY(html.find("The paper next to this study") == std::string::npos);
    }
    std::filesystem::remove_all(dir);
  }

  void studySessionAbandonedTrialIsRunAgainAndCountsAttempts() {
    const auto dir = makeStudyFolder("abandon");
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    {
      StudySession session(dir / "s.sqlite");
      session.selectSubject("P01", 0.0);
      session.beginTrial();
      session.abandonTrial();
      QCOMPARE(session.state(), StudySession::State::kReady);
      runOneTrial(session, 0.0);
      QCOMPARE(session.completedCount(), 1);
    }
    const auto db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kReadOnly);
    QCOMPARE(db.trials("P01")[0].attempts, 2);
    QCOMPARE(db.trials("P01")[0].status, session::TrialStatus::kCompleted);
    std::filesystem::remove_all(dir);
  }

  // A mentored mode's trials at the studio: the expert's station from the study file's mentor
  // block, the runner's set-up (a simulated mentor's link seeded per trial), stored bit for
  // bit as `hattr study run` stores them, the mentor's notes included.
  void studySessionRunsMentoredTrialsAsTheRunnerDoes() {
    const auto dir = makeStudyFolder("mentored");
    const HapticProfile lift = test::writeThenLift(expert_, 1.0);
    io::writeProfileCsv(lift, dir / "lift.csv");
    std::ofstream(dir / "study.json") << test::smallStudyJson(
        "[\"mentor-position\", \"mentor-force\"]", 2.0,
        "[{\"id\": \"P01\", \"participant\": \"person\", \"seed\": 5, \"options\": {\"hand\": \"" +
            (dir / "lift.csv").string() + "\"}}]",
        "flat", kPenUpEnd, "{\"expert\": \"simulated\", \"round_trip_ms\": 20, \"loss_percent\": 5}");
    const session::StudyDefinition study = session::loadStudy(dir / "study.json");
    QVERIFY(study.hasMentoredModes());
    { (void)session::StudyDatabase::create(dir / "runner.sqlite", study); }
    { (void)session::StudyDatabase::create(dir / "studio.sqlite", study); }
    {
      auto db = session::StudyDatabase::open(dir / "runner.sqlite", session::OpenMode::kRunner);
      const auto mentor = net::makeStudyMentor(study.mentor, db.expert(study.skill),
                                               render::parseWorldConfig(study.world.dump(), "w"), study.rate_hz);
      session::StudyRunner runner(db, session::makeScriptParticipant);
      QCOMPARE(runner.run({.mentor = mentor.get()}), 4);
    }
    {
      StudySession session(dir / "studio.sqlite");
      session.selectSubject("P01", 0.0);
      LiveRig rig;
      int mentored = 0;
      while (session.state() != StudySession::State::kFinished) {
        session.skipRest();
        const session::TrialSetup setup = session.currentSetup();
        QVERIFY(setup.live_guidance != nullptr);
        mentored += guidance::isMentored(setup.guidance.mode) ? 1 : 0;
        session.beginTrial();
        const HapticProfile script = io::readProfileCsv(dir / "lift.csv");  // as the runner reads it
        device::ProfileHandScript hand(script, 1.0471975511965976, Vec3(0.0, 0.0, 0.0));
        rig.start(session.environment(), trialRunSpec(setup, false), hand, session::Clock::kSimulated);
        QVERIFY(rig.spec().settle_s >= setup.settle_s);  // at least the mentor's minimum
        rig.advanceSimulated(rig.spec().settle_s);
        rig.advanceSimulated(setup.duration_s);
        const std::string disturbed = session.completeTrial(rig.finish(), 0.0);
        QVERIFY2(disturbed.empty(), disturbed.c_str());
      }
      QCOMPARE(mentored, 2);  // training is mentored, recall is not
    }
    const auto a = session::StudyDatabase::open(dir / "runner.sqlite", session::OpenMode::kReadOnly);
    const auto b = session::StudyDatabase::open(dir / "studio.sqlite", session::OpenMode::kReadOnly);
    const auto ta = a.trials("P01");
    const auto tb = b.trials("P01");
    QCOMPARE(tb.size(), ta.size());
    int with_mentor = 0;
    for (std::size_t i = 0; i < ta.size(); ++i) {
      QCOMPARE(tb[i].status, session::TrialStatus::kCompleted);
      const HapticProfile pa = a.trialProfile(ta[i].id);
      const HapticProfile pb = b.trialProfile(tb[i].id);
      with_mentor += pb.metadata().extra.count("mentor") > 0 ? 1 : 0;
      QVERIFY2(sameButCreationTime(pa, pb), std::to_string(i).c_str());
    }
    QCOMPARE(with_mentor, 2);
    std::filesystem::remove_all(dir);
  }

  // A live mentor whose station does not answer: the trial fails when the settle ends, records
  // nothing, and is marked failed with the reason; the same trial is next again.
  void studySessionFailsAMentoredTrialWhoseExpertIsNotThere() {
    const auto dir = makeStudyFolder("mentor-absent");
    wire::writeKeyFile(dir / "mentor.key", wire::randomKey(), false);
    // A station that never answers: a bound socket nobody reads.
    const wire::UdpSocket silent = wire::UdpSocket::bound({.address = 0x7f000001, .port = 0});
    const std::string connect = fmt::format("127.0.0.1:{}", silent.localEndpoint().port);
    std::ofstream(dir / "study.json") << test::smallStudyJson(
        "[\"mentor-observe\"]", 2.0, "[{\"id\": \"P01\", \"participant\": \"person\"}]", "flat", kPenUpEnd,
        "{\"expert\": \"live\", \"connect\": \"" + connect + "\", \"key\": \"mentor.key\"}");
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    {
      StudySession session(dir / "s.sqlite");
      session.selectSubject("P01", 0.0);
      const session::TrialSetup setup = session.currentSetup();
      QCOMPARE(setup.guidance.mode, guidance::TrainingMode::kMentorObserve);
      session.beginTrial();
      device::ProfileHandScript hand(session.expert());
      LiveRig rig;
      rig.start(session.environment(), trialRunSpec(setup, false), hand, session::Clock::kSimulated);
      rig.advanceSimulated(rig.spec().settle_s + setup.duration_s);
      QVERIFY(rig.status().window_done);
      const session::TrialResult result = rig.finish();
      QVERIFY2(result.failure.find("no answer from the expert's station at " + connect) != std::string::npos,
               result.failure.c_str());
      QCOMPARE(result.end_reason, std::string(session::kEndFailed));
      QVERIFY(result.profile.empty());
      session.failTrial(result.failure);
      QCOMPARE(session.state(), StudySession::State::kReady);
      QCOMPARE(session.currentTrial()->plan.sequence, 0);
      // Without its mentor a mentored run is refused before anything starts.
      session::TrialSetup bare = setup;
      bare.live_guidance = nullptr;
      try {
        rig.start(session.environment(), trialRunSpec(bare, false), hand, session::Clock::kSimulated);
        QFAIL("no error");
      } catch (const InputError& e) {
        QVERIFY2(QString(e.what()).contains("mode MENTOR-OBSERVE: a mentored mode needs an expert's station"), e.what());
      }
      QVERIFY(!rig.active());
    }
    const auto db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kReadOnly);
    const session::TrialRecord first = db.trials("P01")[0];
    QCOMPARE(first.status, session::TrialStatus::kInterrupted);
    QVERIFY2(first.outcome.find("failed: no answer from the expert's station") == 0, first.outcome.c_str());
    std::filesystem::remove_all(dir);
  }

  // The store refuses the trial (as a full disk would): the studio loses nothing. The recording
  // is kept beside the study file, as `hattr study run` keeps it, and the trial runs again.
  void studySessionKeepsARecordingTheStoreRefusesBesideTheStudy() {
    const auto dir = makeStudyFolder("refused");
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    sqlite3* raw = nullptr;
    QCOMPARE(sqlite3_open((dir / "s.sqlite").c_str(), &raw), SQLITE_OK);
    QCOMPARE(sqlite3_exec(raw, "CREATE TRIGGER refuse_all BEFORE INSERT ON samples BEGIN SELECT RAISE(ABORT, 'refuse_all'); END;",
                          nullptr, nullptr, nullptr),
             SQLITE_OK);
    sqlite3_close(raw);
    {
      StudySession session(dir / "s.sqlite");
      session.selectSubject("P01", 0.0);
      try {
        runOneTrial(session, 1.0);
        QFAIL("the refused store was not reported");
      } catch (const Error& e) {
        QVERIFY2(QString(e.what()).contains(QString::fromStdString("its recording is kept in " +
                                                                   (dir / "s.sqlite.unstored" / "trials" / "P01").string())),
                 e.what());
      }
      QCOMPARE(session.state(), StudySession::State::kReady);
      QCOMPARE(session.completedCount(), 0);
      QCOMPARE(session.currentTrial()->plan.sequence, 0);
    }
    int kept = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir / "s.sqlite.unstored")) {
      if (entry.is_regular_file() && !io::readProfileCsv(entry.path()).empty()) ++kept;
    }
    QCOMPARE(kept, 1);
    std::filesystem::remove_all(dir);
  }

  void studySessionRefusesAStudyAnotherRunnerHolds() {
    const auto dir = makeStudyFolder("lock");
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    StudySession first(dir / "s.sqlite");
    try {
      StudySession second(dir / "s.sqlite");
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("s.sqlite"), e.what());
    }
    std::filesystem::remove_all(dir);
  }

  void studySessionRefusesAFileThatIsNoStudy() {
    const auto dir = test::freshTempDir("nostudy");
    std::ofstream(dir / "x.sqlite") << "hello";
    try {
      StudySession session(dir / "x.sqlite");
      QFAIL("no error");
    } catch (const InputError& e) {
      QVERIFY2(QString(e.what()).contains("x.sqlite"), e.what());
    }
    std::filesystem::remove_all(dir);
  }

 private:
  std::filesystem::path makeStudyFolder(const std::string& name) {
    const auto dir = test::freshTempDir(name);
    io::writeProfileCsv(expert_, dir / "expert.csv");
    std::ofstream(dir / "study.json") << studyJson();
    return dir;
  }

  void runOneTrial(StudySession& session, double now) {
    const session::TrialSetup setup = session.currentSetup();
    session.beginTrial();
    device::ProfileHandScript hand(session.expert());
    LiveRig rig;
    rig.start(session.environment(), trialRunSpec(setup, false), hand, session::Clock::kSimulated);
    rig.advanceSimulated(setup.settle_s + setup.duration_s);
    session.completeTrial(rig.finish(), now);
  }

  std::unique_ptr<session::TrialEnvironment> environment_;
  HapticProfile expert_;
  std::shared_ptr<const guidance::ReferenceTrajectory> reference_;
};

QTEST_GUILESS_MAIN(StudioRigTest)
#include "studio_rig_test.moc"
