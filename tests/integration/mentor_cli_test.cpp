// Runs the real `hattr mentor lead` in the background on loopback (127.0.0.1 only) and the real
// `hattr mentor follow` / `hattr study run` against it: two stations recording both sides, and
// a study whose mentored trials are each a session of a live expert's station.

#include <signal.h>


#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"
#include "net/writing_script.hpp"
#include "support/background_process.hpp"
#include "support/run_command.hpp"
#include "support/test_support.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;

using test::RunResult;
using test::runHattr;

/// The expert's writing (a figure of eight in 2.4 s, then the pen lifted) and the trainee's
/// (the same, 3 mm right and 2 mm down), written to the folder.
void writeScripts(const test::TempDir& dir) {
  const HapticProfile expert = test::figureEightThenLift(2.4);
  io::writeProfileCsv(expert, dir / "expert.csv");
  io::writeProfileCsv(test::offsetScript(expert, Vec3(0.003, -0.002, 0.0)), dir / "trainee.csv");
}

std::string makeKey(const test::TempDir& dir) {
  const auto key = (dir / "mentor.key").string();
  const RunResult r = runHattr(dir, "device keygen --out " + key, "keygen");
  if (r.exit_code != 0) throw std::runtime_error("keygen failed: " + r.err);
  return key;
}

/// `hattr mentor lead` on an ephemeral loopback port, its simulated expert writing expert.csv.
test::BackgroundProcess startLead(const test::TempDir& dir, const std::string& key, std::vector<std::string> extra) {
  std::vector<std::string> args = {test::builtFile("HATTR_CLI"), "mentor", "lead", "--listen", "127.0.0.1:0", "--key", key,
                                   "--hand", (dir / "expert.csv").string(), "--json"};
  args.insert(args.end(), extra.begin(), extra.end());
  return test::BackgroundProcess(args, dir / "lead.err");
}

constexpr const char* kTraineePen = "'sim://pen?hand_stiffness_N_per_m=80'";

TEST(MentorCli, LeadAndFollowOverLoopbackRecordBothSides) {
  test::TempDir dir;
  writeScripts(dir);
  const std::string key = makeKey(dir);
  test::BackgroundProcess lead = startLead(dir, key, {"--record", (dir / "expert-side.csv").string()});
  ASSERT_THAT(lead.firstLine(), HasSubstr("listening on 127.0.0.1:"));

  const RunResult follow = runHattr(dir, "mentor follow --connect " + lead.address() + " --key " + key +
                                             " --coupling position --device " + kTraineePen + " --hand " +
                                             (dir / "trainee.csv").string() + " --record " +
                                             (dir / "trainee-side.csv").string() + " --json");
  ASSERT_EQ(follow.exit_code, 0) << follow.err;
  const std::string lead_rest = lead.readRest();
  EXPECT_EQ(lead.wait(), 0) << test::readText(dir / "lead.err");

  // The follower's summary and the leader's: linked, packets both ways, no failure. The
  // sessions last a wall-clock time, so how many ticks fit depends on the host (a loaded CI
  // host froze both loops for ~0.4 s: 1705 samples where 2100 are usual): the counts are
  // checked against each side's own recording, not against the clock.
  const HapticProfile expert_side = io::readProfileCsv(dir / "expert-side.csv");
  const HapticProfile trainee_side = io::readProfileCsv(dir / "trainee-side.csv");
  const auto follower = nlohmann::json::parse(follow.out.substr(follow.out.find('{')));
  EXPECT_EQ(follower["failure"], "");
  EXPECT_GT(follower["peers_received"].get<double>(), 0.5 * static_cast<double>(trainee_side.size()));
  const auto leader = nlohmann::json::parse(lead_rest.substr(lead_rest.find('{')));
  EXPECT_EQ(leader["failure"], "");
  EXPECT_GT(leader["peers_received"].get<double>(), 0.5 * static_cast<double>(expert_side.size()));

  // Both sides are haptic profiles (at least a second of the linked session), the coupling named in each.
  EXPECT_GT(expert_side.size(), 1000u);
  EXPECT_GT(trainee_side.size(), 1000u);
  EXPECT_EQ(trainee_side.metadata().extra.at("coupling"), "position");
  EXPECT_EQ(expert_side.metadata().extra.at("mentor_role"), "leader");
}

TEST(MentorCli, ALeadServesEachMentoredTrialOfAStudyAsItsOwnSession) {
  test::TempDir dir;
  writeScripts(dir);
  const std::string key = makeKey(dir);
  test::BackgroundProcess lead = startLead(dir, key, {"--sessions", "0", "--record-dir", (dir / "sessions").string()});
  ASSERT_THAT(lead.firstLine(), HasSubstr("listening on 127.0.0.1:"));

  // Two mentored training trials, then an unassisted recall trial, in real time. A loaded host
  // may drop the 10 ms link hold: such a trial is kept flagged, not repeated, so there is one
  // session per trial.
  test::writeText(dir / "study.json", R"({
    "name": "live mentor", "skill": "eight", "experts": {"eight": "expert.csv"},
    "modes": ["mentor-position"],
    "protocol": {"training_trials": 2, "recall_trials": 1, "rest_s": 0, "analyzed_recall_trials": [1],
                 "disturbed_trials": "flag"},
    "mentor": {"expert": "live", "connect": ")" + lead.address() + R"(", "key": "mentor.key"},
    "device": "sim://pen?hand_stiffness_N_per_m=80",
    "world": {"relief": {"kind": "flat"}},
    "subjects": [{"id": "T1", "participant": "script", "options": {"hand": ")" + (dir / "trainee.csv").string() + R"("}}]
  })");
  const auto db = (dir / "study.sqlite").string();
  ASSERT_EQ(runHattr(dir, "study init " + (dir / "study.json").string() + " --db " + db, "init").exit_code, 0);
  const RunResult run = runHattr(dir, "study run --db " + db + " --clock real --quiet", "study");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("ran 3 trials"));

  // The trainee's side: the study's trials, the mentored ones saying who mentored.
  const auto study = session::StudyDatabase::open(db, session::OpenMode::kReadOnly);
  int mentored = 0;
  for (const auto& t : study.trials()) {
    ASSERT_EQ(t.status, session::TrialStatus::kCompleted);
    const auto extra = study.trialProfile(t.id).metadata().extra;
    if (t.plan.phase == session::kPhaseTraining) {
      ++mentored;
      EXPECT_EQ(extra.at("mentor"), "live expert at " + lead.address());
      EXPECT_EQ(extra.at("coupling"), "position");
      // Coupled throughout: PEERs for a good share of the trial's own ticks (not a count per
      // wall-clock second: a stalled host delivers fewer in the same time).
      EXPECT_GT(std::stod(extra.at("peer_packets_received")), 0.2 * static_cast<double>(study.trialProfile(t.id).size()));
    } else {
      EXPECT_FALSE(extra.contains("coupling"));
    }
  }
  EXPECT_EQ(mentored, 2);

  // The expert's side: one session per mentored trial, each ended by the trainee's BYE; the
  // station serves until it is told to stop.
  lead.signal(SIGTERM);
  const std::string lead_rest = lead.readRest();
  EXPECT_EQ(lead.wait(), 0) << test::readText(dir / "lead.err");
  const auto summary = nlohmann::json::parse(lead_rest.substr(lead_rest.find("{\n")));
  ASSERT_EQ(summary["sessions"].size(), 2u) << lead_rest;
  // Each session's figures are its own, not counted on from the session before: the expert's
  // station records every tick from the link's start, and hears at most one PEER a tick
  // (slack for ticks the host delayed); counted on, the second would hold both sessions'.
  for (const auto& s : summary["sessions"]) {
    EXPECT_EQ(s["failure"], "");
    EXPECT_GT(s["peers_received"].get<double>(), 0.2 * s["samples"].get<double>()) << s.dump();
    EXPECT_LT(s["peers_received"].get<double>(), s["samples"].get<double>() + 500.0) << s.dump();
  }
  EXPECT_GT(io::readProfileCsv(dir / "sessions" / "session-001.csv").size(), 0u);
  EXPECT_GT(io::readProfileCsv(dir / "sessions" / "session-002.csv").size(), 0u);
}

TEST(MentorCli, AStudyWhoseLiveMentorDoesNotAnswerFailsTheTrialAndLosesNothing) {
  test::TempDir dir;
  writeScripts(dir);
  (void)makeKey(dir);
  // Port 9 (discard): nothing answers there.
  test::writeText(dir / "study.json", R"({
    "name": "absent mentor", "skill": "eight", "experts": {"eight": "expert.csv"},
    "modes": ["basic", "mentor-force"], "order": {"kind": "fixed"},
    "protocol": {"training_trials": 1, "recall_trials": 1, "rest_s": 0, "analyzed_recall_trials": [1]},
    "mentor": {"expert": "live", "connect": "127.0.0.1:9", "key": "mentor.key"},
    "world": {"relief": {"kind": "flat"}},
    "subjects": [{"id": "T1", "participant": "script"}]
  })");
  const auto db = (dir / "study.sqlite").string();
  ASSERT_EQ(runHattr(dir, "study init " + (dir / "study.json").string() + " --db " + db, "init").exit_code, 0);
  const RunResult run = runHattr(dir, "study run --db " + db + " --clock real --quiet", "study");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.err, HasSubstr("no answer from the expert's station at 127.0.0.1:9"));
  // BASIC's two trials are kept; the mentored trial waits to be run again.
  const auto status = nlohmann::json::parse(runHattr(dir, "study status --json --db " + db, "status").out);
  EXPECT_EQ(status["trials_completed"], 2);
  EXPECT_EQ(status["subjects"][0]["next"]["mode"], "MENTOR-FORCE");

  // A lead asked to serve many sessions into one file is refused before it listens.
  const RunResult refused = runHattr(dir, "mentor lead --listen 127.0.0.1:0 --key " + (dir / "mentor.key").string() +
                                              " --sessions 0 --record one.csv", "refused");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_THAT(refused.err, HasSubstr("with --sessions 0 each session is its own file: use --record-dir DIR"));
}

}  // namespace
}  // namespace hattr
