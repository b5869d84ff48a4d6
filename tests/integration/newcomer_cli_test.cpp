// What a newcomer meets first (issue 20): a mistyped command is named with the closest one,
// `hattr devices` gives every parameter's default, servo-check says it takes twice
// --seconds, and long commands show progress on a terminal but print nothing of it to a
// pipe. A terminal is a real pseudo-terminal made by util-linux's `script`.

#include <sys/wait.h>

#include <cstdlib>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/run_command.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

using test::RunResult;

/// hattr with stdout and stderr to files (as in a script).
RunResult runPiped(const test::TempDir& dir, const std::string& args) {
  const auto out = dir / "stdout.txt";
  const auto err = dir / "stderr.txt";
  const std::string command = std::string(test::builtFile("HATTR_CLI")) + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, test::readText(out), test::readText(err)};
}

/// hattr on a pseudo-terminal (stdout and stderr both): what a person at a terminal sees.
RunResult runOnTerminal(const test::TempDir& dir, const std::string& args) {
  const auto seen = dir / "terminal.txt";
  const std::string command = "TERM=xterm script -qec \"" + std::string(test::builtFile("HATTR_CLI")) + " " + args + "\" /dev/null >" +
                              seen.string() + " 2>&1 </dev/null";
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, test::readText(seen), ""};
}

TEST(Newcomer, AMistypedCommandIsNamedWithTheClosestOne) {
  test::TempDir dir;
  const RunResult top = runPiped(dir, "stdy");
  EXPECT_EQ(top.exit_code, 2);
  EXPECT_THAT(top.err, HasSubstr("unknown command \"stdy\" after \"hattr\": did you mean \"hattr study\"?"));
  EXPECT_THAT(top.err, Not(HasSubstr("A subcommand is required")));

  const RunResult nested = runPiped(dir, "study rnu --db x.sqlite");
  EXPECT_EQ(nested.exit_code, 2);
  EXPECT_THAT(nested.err, HasSubstr("unknown command \"rnu\" after \"hattr study\": did you mean \"hattr study run\"?"));

  const RunResult optional_level = runPiped(dir, "devices chek sim://pen");
  EXPECT_EQ(optional_level.exit_code, 2);
  EXPECT_THAT(optional_level.err, HasSubstr("did you mean \"hattr devices check\"?"));
  const RunResult alias = runPiped(dir, "device chek sim://pen");  // `device` is the alias of `devices`
  EXPECT_EQ(alias.exit_code, 2);
  EXPECT_THAT(alias.err, HasSubstr("unknown command \"chek\" after \"hattr devices\": did you mean"));

  // Options before the command word are CLI11's to judge; a known command still runs.
  EXPECT_EQ(runPiped(dir, "--version").exit_code, 0);
  EXPECT_EQ(runPiped(dir, "world --help").exit_code, 0);

  // Nothing close: no guess, the list of commands.
  const RunResult far = runPiped(dir, "xyzzy");
  EXPECT_EQ(far.exit_code, 2);
  EXPECT_THAT(far.err, Not(HasSubstr("did you mean")));
  EXPECT_THAT(far.err, HasSubstr("(commands: profile, import, servo-check"));

  // A positional argument is not taken for a command.
  const RunResult positional = runPiped(dir, "profile info no-such-file.csv");
  EXPECT_EQ(positional.exit_code, 2);
  EXPECT_THAT(positional.err, HasSubstr("no-such-file.csv: cannot open for reading"));
}

TEST(Newcomer, DevicesGivesEveryNumericParameterItsRangeAndDefault) {
  test::TempDir dir;
  const RunResult devices = runPiped(dir, "devices");
  ASSERT_EQ(devices.exit_code, 0) << devices.err;
  int ranges = 0;
  std::istringstream lines(devices.out);
  for (std::string line; std::getline(lines, line);) {
    if (line.find(" in [") == std::string::npos) continue;
    ++ranges;
    EXPECT_THAT(line, HasSubstr(", default ")) << "a parameter without its default";
  }
  EXPECT_GE(ranges, 13);  // the simulated pen's 11 keys and udp://'s 2
  EXPECT_THAT(devices.out, HasSubstr("hold_ms"));
}

TEST(Newcomer, ServoCheckSaysItTakesTwiceItsSeconds) {
  test::TempDir dir;
  const RunResult help = runPiped(dir, "servo-check --help");
  ASSERT_EQ(help.exit_code, 0);
  EXPECT_THAT(help.out, HasSubstr("the bare sleep loop (floor) and then the servo loop: the check takes twice this"));
}

TEST(Newcomer, ServoCheckShowsItsTwoPhasesOnATerminalAndNothingInAPipe) {
  test::TempDir dir;
  const RunResult terminal = runOnTerminal(dir, "servo-check --seconds 0.3");
  ASSERT_EQ(terminal.exit_code, 0) << terminal.out;
  EXPECT_THAT(terminal.out, HasSubstr("servo-check 1/2: the bare sleep loop (floor) ["));
  EXPECT_THAT(terminal.out, HasSubstr("servo-check 2/2: the servo loop ["));
  EXPECT_THAT(terminal.out, HasSubstr("0.0/0.3 s"));

  const RunResult piped = runPiped(dir, "servo-check --seconds 0.3");
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  EXPECT_THAT(piped.err, Not(HasSubstr("servo-check 1/2")));
  EXPECT_THAT(piped.err, Not(HasSubstr("\r")));
}

/// A small study: 3 subjects, 1 training and 3 recall trials per mode, scripted participants.
std::string smallStudy(const test::TempDir& dir) {
  std::string script = "# skill: loop\nt_s,x_mm,y_mm,z_mm,fx_N,fy_N,fz_N,pen_down_bool\n";
  for (int i = 0; i <= 50; ++i) script += std::to_string(i * 0.01) + "," + std::to_string(i * 0.2) + ",0,0,0,0,-1.2,1\n";
  test::writeText(dir / "expert.csv", script);
  test::writeText(dir / "study.json", R"({"name": "progress", "skill": "loop", "experts": {"loop": "expert.csv"},
      "protocol": {"training_trials": 1, "recall_trials": 3, "rest_s": 0}, "world": {"relief": {"kind": "flat"}},
      "subjects": {"count": 3, "participant": "script", "options": {"jitter_mm": 2.0}}})");
  const std::string db = (dir / "s.sqlite").string();
  EXPECT_EQ(runPiped(dir, "study init " + (dir / "study.json").string() + " --db " + db).exit_code, 0);
  return db;
}

TEST(Newcomer, StudyRunAndReportShowProgressOnATerminalAndNothingInAPipe) {
  test::TempDir dir;
  const std::string db = smallStudy(dir);
  const RunResult piped_run = runPiped(dir, "study run --db " + db + " --max-trials 2");
  ASSERT_EQ(piped_run.exit_code, 0) << piped_run.err;
  EXPECT_EQ(piped_run.err, "");
  EXPECT_THAT(piped_run.out, HasSubstr("ran 2 trials"));

  const RunResult run = runOnTerminal(dir, "study run --db " + db);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  // A subject's line (at most ten draws a second, the last always: which subjects show between
  // depends on the host's speed).
  EXPECT_THAT(run.out, HasSubstr("study run: S0"));
  EXPECT_THAT(run.out, HasSubstr("/34 trials"));  // 36 planned, 2 done before
  EXPECT_THAT(run.out, HasSubstr("ran 34 trials"));

  const RunResult report = runOnTerminal(dir, "study report --db " + db + " --out " + (dir / "report").string());
  ASSERT_EQ(report.exit_code, 0) << report.out;
  EXPECT_THAT(report.out, HasSubstr("study report: scoring recall trials ["));
  EXPECT_THAT(report.out, HasSubstr("18/18 trials"));  // recall trials 2 and 3 of 3 subjects × 3 modes
  EXPECT_THAT(report.out, HasSubstr("study report: writing the report and figures"));

  const RunResult piped_report =
      runPiped(dir, "study report --force --db " + db + " --out " + (dir / "report").string());
  ASSERT_EQ(piped_report.exit_code, 0) << piped_report.err;
  EXPECT_EQ(piped_report.err, "");
}

TEST(Newcomer, SimAaAndSweepShowProgressOnATerminalAndNothingInAPipe) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("about 100 simulated trials in three CLI runs, 107 s under it; the progress is "
                                    "the main thread's, and the studies' subjects at once run under it in "
                                    "InSilicoStudy.SubjectsRunAtOnceGiveTheSameTrialsToTheBitAsOneAtATime");
  test::TempDir dir;
  const std::string out = (dir / "sim").string();
  // The built-in loop, not the paper's ந: about half the writing, and --glyph reaches every study.
  const RunResult aa = runOnTerminal(dir, "sim aa --seeds 2 --subjects 2 --trials 2 --glyph loop --out " + out);
  ASSERT_EQ(aa.exit_code, 0) << aa.out;
  EXPECT_THAT(aa.out, HasSubstr("A/A: study 2 of 2 ["));
  EXPECT_THAT(aa.out, HasSubstr("A/A check (2 seeds, 2 subjects, 2+2 trials per mode, glyph loop,"));
  EXPECT_THAT(test::readText(dir / "sim" / "aa-loop-position-plan-002" / "study.json"), HasSubstr("\"skill\": \"loop\""));
  // Another glyph into the same folder keeps the first run's studies (the folders name the glyph).
  ASSERT_EQ(runOnTerminal(dir, "sim aa --seeds 1 --subjects 2 --trials 2 --glyph a --out " + out).exit_code, 0);
  EXPECT_THAT(test::readText(dir / "sim" / "aa-small-a-position-plan-001" / "study.json"), HasSubstr("\"skill\": \"small-a\""));
  EXPECT_THAT(test::readText(dir / "sim" / "aa-loop-position-plan-001" / "study.json"), HasSubstr("\"skill\": \"loop\""));

  const RunResult sweep =
      runOnTerminal(dir, "sim sweep --param slow_rate --values 0.01 --subjects 2 --trials 2 --glyph loop --out " + out);
  ASSERT_EQ(sweep.exit_code, 0) << sweep.out;
  EXPECT_THAT(sweep.out, HasSubstr("sweep: slow_rate = 0.01 ["));
  EXPECT_THAT(test::readText(dir / "sim" / "sweep-loop-slow_rate-0.01" / "study.json"), HasSubstr("\"skill\": \"loop\""));

  const RunResult piped = runPiped(dir, "sim aa --seeds 1 --subjects 2 --trials 2 --glyph loop --out " + out + "-piped");
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  EXPECT_EQ(piped.err, "");
}

}  // namespace
}  // namespace hattr
