// hattr sim plan: a plan killed with SIGKILL and resumed gives the unbroken run's answer; one
// process, two MPI ranks (a real mpirun) and two shards on one state folder give the same
// answer; its page and JSON; bad input exits 2 with the reason.

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/run_command.hpp"
#include "support/thread_sanitizer.hpp"

extern char** environ;

namespace hattr {
namespace {

using ::testing::HasSubstr;
using test::hattrCli;
using test::kMpiEnvironment;
using test::mpirun;
using test::RunResult;

/// A small plan of the paper's study that visits four designs (32 replicates, about 8 s in the
/// release build): the loop glyph, 2 + 2 trials, 3 to 6 subjects, batches of 2, α 0.5 so that
/// its power is away from 0 (every design undecided, so each gets its 8).
const std::string kPlan =
    "sim plan --trials 2 --glyph loop --alpha 0.5 --power 0.2 --min-subjects 3 --max-subjects 6 --batch 2 "
    "--max-replicates 8 --seed 3 --threads 1 --quiet --json";

/// What a plan answers, without its run's times.
nlohmann::json answerOf(const std::string& out) {
  nlohmann::json j = nlohmann::json::parse(out);
  j.erase("run");
  return j;
}

/// `command` in the background through the shell, its output in files; its pid.
pid_t startInBackground(const std::string& command) {
  const std::string line = "exec " + command;
  const char* argv[] = {"/bin/sh", "-c", line.c_str(), nullptr};
  pid_t pid = 0;
  if (posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ) != 0) return -1;
  return pid;
}

int waitFor(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::size_t linesIn(const std::filesystem::path& file) {
  if (!std::filesystem::exists(file)) return 0;
  const std::string text = test::readText(file);
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

TEST(PlanCli, AKilledPlanResumesToTheUnbrokenRunsAnswer) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("64 simulated replicates on one thread; the state folder's own test "
                                    "(PlanState.*) runs under it");
  test::TempDir dir;
  const RunResult whole = test::runCommand(dir, hattrCli(), kPlan + " --html " + (dir / "plan.html").string(), "whole");
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const nlohmann::json answer = answerOf(whole.out);
  ASSERT_EQ(answer["searches"].size(), 1u);
  ASSERT_EQ(answer["searches"][0]["points"].size(), 4u);
  EXPECT_THAT(test::readText(dir / "plan.html"), HasSubstr("<svg"));

  // Killed with SIGKILL once its second design has begun, then resumed.
  const std::filesystem::path state = dir / "state";
  const std::filesystem::path lines = state / "outcomes-main.jsonl";
  const pid_t pid = startInBackground(fmt::format("{} {} --state {} >{} 2>{}", hattrCli(), kPlan, state.string(),
                                                  (dir / "killed.out").string(), (dir / "killed.err").string()));
  ASSERT_GT(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
  while (linesIn(lines) < 14 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(pid, SIGKILL);
  EXPECT_EQ(waitFor(pid), 128 + SIGKILL) << "the plan ended before it was killed";
  const std::size_t kept = linesIn(lines);
  EXPECT_GE(kept, 14u);
  EXPECT_LT(kept, 32u);
  const RunResult resumed = test::runCommand(dir, hattrCli(), kPlan + " --state " + state.string(), "resumed");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_EQ(answerOf(resumed.out), answer);
  const int run_now = nlohmann::json::parse(resumed.out)["run"]["replicates_run"].get<int>();
  EXPECT_EQ(static_cast<std::size_t>(run_now), 32u - kept);  // only what the kill left

  // Resumed with other options: refused, the folder kept.
  const RunResult other = test::runCommand(dir, hattrCli(), kPlan + " --confidence 0.9 --state " + state.string(), "other");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_THAT(other.err, HasSubstr("the folder holds another plan (its \"search\" differs)"));
}

TEST(PlanCli, OneProcessTwoMpiRanksAndTwoShardsGiveTheSameAnswer) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("the plan's replicates three more times; the exchange of outcomes is tested in "
                                    "PlanState.* and the power analysis's ranks in PowerCli.*");
  test::TempDir dir;
  const RunResult one = test::runCommand(dir, hattrCli(), kPlan, "one");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const nlohmann::json answer = answerOf(one.out);

  // Two ranks of a real mpirun (not under the sanitizers: Open MPI is not instrumented).
  if (!test::kSanitized) {
    const std::string launcher = mpirun();
    ASSERT_FALSE(launcher.empty()) << "mpirun not found: install openmpi-bin (scripts/install-deps)";
    const RunResult ranks = test::runCommand(dir, kMpiEnvironment + launcher,
                                             "-n 2 " + hattrCli() + " " + kPlan + " --state " +
                                                 (dir / "mpi-state").string(),
                                             "mpi");
    ASSERT_EQ(ranks.exit_code, 0) << ranks.err << ranks.out;
    EXPECT_EQ(answerOf(ranks.out), answer);
    EXPECT_EQ(nlohmann::json::parse(ranks.out)["run"]["processes"], 2);
    EXPECT_EQ(linesIn(dir / "mpi-state" / "outcomes-main.jsonl"), 32u);  // rank 0 wrote every rank's
  }

  // Two shards at once on one folder, each running half of every batch.
  const std::filesystem::path state = dir / "shards";
  pid_t shards[2];
  for (int s : {0, 1}) {
    shards[s] = startInBackground(fmt::format("{} {} --state {} --shard {}/2 >{} 2>{}", hattrCli(), kPlan, state.string(),
                                              s, (dir / fmt::format("shard{}.out", s)).string(),
                                              (dir / fmt::format("shard{}.err", s)).string()));
    ASSERT_GT(shards[s], 0);
  }
  for (int s : {0, 1}) {
    EXPECT_EQ(waitFor(shards[s]), 0) << test::readText(dir / fmt::format("shard{}.err", s));
    EXPECT_EQ(answerOf(test::readText(dir / fmt::format("shard{}.out", s))), answer);
    EXPECT_EQ(linesIn(state / fmt::format("outcomes-shard-{}-of-2.jsonl", s)), 16u);  // its half
  }
}

TEST(PlanCli, BadInputIsRefusedWithExitTwoAndTheReason) {
  test::TempDir dir;
  const std::string calibration = "sim plan --calibration two-sample --effect-size 0.5 --quiet";
  const auto refused = [&](const std::string& args, const std::string& why) {
    const RunResult r = test::runCommand(dir, hattrCli(), args, "refused");
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(why)) << args;
  };
  refused(calibration + " --power 1", "--power: expected a target power in (0, 1), got 1");
  refused(calibration + " --power 0", "--power: expected a target power in (0, 1), got 0");
  refused(calibration + " --alpha 1.5", "--alpha: expected a level in (0, 1), got 1.5");
  refused(calibration + " --alpha 0", "--alpha: expected a level in (0, 1), got 0");
  refused(calibration + " --min-subjects 50 --max-subjects 40", "--max-subjects: expected at least --min-subjects (50)");
  refused(calibration + " --shard 0/2", "--shard: shards share their replicates through a folder: expected --state DIR");
  refused(calibration + " --compare A-B", "the calibration design has two conditions: expected mode");
  refused("sim plan --calibration three-arm --effect-size 0.5", "--calibration: expected two-sample or paired");
  refused("sim plan --calibration paired --effect-size 0", "--effect-size: expected a Cohen's d with 0 < |d| <= 10, got 0");
  refused("sim plan --trials 2 --compare ALPHA-MIRROR --quiet",
          "--compare ALPHA-MIRROR: expected \"mode\" or two of the design's BASIC, PCONTROL, ALPHA");
  refused("sim plan --trials 2 --hypothesis mirror --quiet", "--hypothesis");
  refused("sim plan --trials 2 --outcome speed --quiet", "--outcome: expected shape");
  refused("sim plan --trials 2 --analysis lme --quiet", "--analysis: expected anova (sim power's) or mixed");
  refused(calibration + " --analysis mixed", "--calibration: the calibration design's outcome is its normal value");
  refused("sim plan --trials 2 --min-subjects 2 --quiet", "--min-subjects: a study's design needs at least 3 subjects");
  // Limits no design meets: 0.05 lab hours in all, less than one subject's trials.
  refused("sim plan --trials 2 --max-lab-hours 0.05 --quiet", "the limits leave no design to search");
  refused("sim plan --trials 2 --max-hours-per-subject 0.01 --quiet", "lab hours per subject, over the limit of 0.01 h");

  // A search that ends without a design says so plainly (exit 0: the answer is "none").
  const RunResult none = test::runCommand(dir, hattrCli(),
                                          "sim plan --calibration two-sample --effect-size 0.1 --max-subjects 20 --quiet",
                                          "none");
  EXPECT_EQ(none.exit_code, 0) << none.err;
  EXPECT_THAT(none.out, HasSubstr("no design within 20 subjects per group reaches 80 % power: best "));
  EXPECT_THAT(none.out, HasSubstr(" at 20"));
}

}  // namespace
}  // namespace hattr
