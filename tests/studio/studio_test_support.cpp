#include "studio_test_support.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "hattr/device/hand.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/session/study_runner.hpp"

namespace hattr::studio::test {

HapticProfile figureEightScript(double duration_s, double normal_N, Vec3 centre) {
  constexpr double kTwoPi = 6.283185307179586;
  HapticProfile script(ProfileMetadata{.subject = "script", .skill = "eight"});
  const int n = static_cast<int>(std::lround(duration_s * 200.0));
  for (int i = 0; i <= n; ++i) {
    const double t = duration_s * i / n;
    const double w = kTwoPi / duration_s;
    Sample s;
    s.t_s = t;
    s.p_WT = centre + Vec3(0.020 * std::sin(w * t), 0.015 * std::sin(2.0 * w * t), 0.0);
    s.v_WT = Vec3(0.020 * w * std::cos(w * t), 0.030 * w * std::cos(2.0 * w * t), 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -normal_N);
    s.pen_down = true;
    s.in_contact = true;
    script.append(s);
  }
  return script;
}

render::WorldConfig flatWorld() {
  render::WorldConfig world;
  world.relief.kind = render::ReliefConfig::Kind::kFlat;
  return world;
}

HapticProfile recordExpert(session::TrialEnvironment& environment, double duration_s) {
  const HapticProfile script = figureEightScript(duration_s);
  device::ProfileHandScript hand(script);
  session::TrialSetup setup;
  setup.duration_s = duration_s + 0.1;
  setup.metadata.subject = "expert";
  setup.metadata.skill = "eight";
  return session::runTrial(environment, setup, hand).profile;
}

std::string smallStudyJson(const std::string& modes, double rest_s, const std::string& subjects,
                           const std::string& relief, const std::string& trial_end, const std::string& mentor) {
  // Kept out of the test files: moc does not parse raw string literals. Disturbed trials are
  // flagged, not repeated: the studio's real-time trials run on whatever load the host has, and
  // the policies have tests of their own (DisturbedTrials.*).
  return R"({"format": "hattr-study/1", "name": "studio test", "skill": "eight",)"
         R"("experts": {"eight": "expert.csv"}, "modes": )" +
         modes + R"(, "protocol": {"training_trials": 1, "recall_trials": 1, "rest_s": )" + std::to_string(rest_s) +
         ", " + trial_end +
         R"(, "disturbed_trials": "flag"}, "order": {"kind": "fixed"}, "device": "sim://pen",)"
         R"("world": {"relief": {"kind": ")" +
         relief +
         R"("}}, "rate_hz": 1000, "indexing": "time",)"
         R"("subjects": )" +
         subjects + (mentor.empty() ? "" : R"(, "mentor": )" + mentor) + "}";
}

std::string designStudyJson(double rest_s) {
  return R"({"format": "hattr-study/1", "name": "studio design", "skill": "eight", "experts": {"eight": "expert.csv"},)"
         R"("protocol": {"rest_s": )" + std::to_string(rest_s) +
         R"(, "trial_end": {"pen_up_s": 0.5}, "disturbed_trials": "flag"}, "device": "sim://pen",)"
         R"("world": {"relief": {"kind": "flat"}}, "rate_hz": 1000,)"
         R"("groups": [{"name": "path", "strategies": ["pcontrol"], "subjects": [{"id": "P01", "participant": "person"}]}],)"
         R"("sessions": [{"day": 0, "blocks": [{"phase": "training", "strategy": "group", "trials": 1},)"
         R"({"phase": "post-test", "trials": 1}]}, {"day": 1, "blocks": [{"phase": "retention", "trials": 1}]}]})";
}

HapticProfile writeThenLift(const HapticProfile& writing, double lift_s) {
  HapticProfile script = writing;
  const Sample last = writing.samples().back();
  for (int i = 1; i * 0.01 <= lift_s + 1e-9; ++i) {
    Sample s = last;
    s.t_s = last.t_s + i * 0.01;
    s.p_WT.z() = 0.005;
    s.v_WT.setZero();
    s.f_user_W.setZero();
    s.f_guide_W.setZero();
    s.pen_down = false;
    s.in_contact = false;
    script.append(s);
  }
  return script;
}

RealTimeOutcome passesUnlessTheHostStalls(const RealTimeAttempt& attempt, int tries) {
  RealTimeOutcome outcome;
  for (int k = 1; k <= tries; ++k) {
    std::uint64_t stalls = 0;
    outcome.failures = attempt(stalls);
    if (outcome.failures.empty()) {
      outcome.passed = true;
      return outcome;
    }
    if (stalls == 0) return outcome;  // no stall explains it: the test's own failure
    std::printf("attempt %d of %d: the host stalled the loop %llu times; it failed with: %s\n", k, tries,
                static_cast<unsigned long long>(stalls), outcome.failures.c_str());
  }
  outcome.every_attempt_stalled = true;
  return outcome;
}

std::filesystem::path reportStudy(const std::filesystem::path& dir, bool complete, int subjects) {
  HapticProfile expert({.subject = "expert", .skill = "curve", .nominal_rate_hz = 100.0});
  for (int i = 0; i <= 40; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.0005 * i, 0.004 * std::sin(i * 0.15), 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0 - 0.3 * std::sin(i * 0.2));
    s.pen_down = true;
    expert.append(s);
  }
  io::writeProfileCsv(expert, dir / "expert.csv");
  std::ofstream(dir / "study.json")
      << R"({"name": "report test", "skill": "curve", "experts": {"curve": "expert.csv"},)"
         R"("protocol": {"training_trials": 1, "recall_trials": 3, "rest_s": 0, "tail_s": 0.05},)"
         R"("world": {"relief": {"kind": "flat"}},)"
         R"("subjects": {"count": )" << subjects << R"(, "participant": "script", "options": {"jitter_mm": 2.0}}})";
  const auto db_file = dir / "s.sqlite";
  { (void)session::StudyDatabase::create(db_file, session::loadStudy(dir / "study.json")); }
  if (complete) {
    session::StudyDatabase db = session::StudyDatabase::open(db_file, session::OpenMode::kRunner);
    session::StudyRunner(db, session::makeScriptParticipant).run({});
  }
  return db_file;
}

std::filesystem::path freshTempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("hattr-studio-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace hattr::studio::test
