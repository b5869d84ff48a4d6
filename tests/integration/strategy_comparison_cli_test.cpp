// hattr sim compare-strategies on a small design: a row per phase and a column per strategy
// under each hypothesis, an A/A check, and what no strategy can change (the unguided group is
// the same under a hypothesis that differs only in how guidance is felt).

#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/run_command.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;
using test::RunResult;
using test::runHattr;

TEST(StrategiesCli, TabulatesEachPhaseUnderEachStrategyAndHypothesisWithAnAaCheck) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("one thread (--threads 1) simulating and scoring 4 studies; subjects at once run "
                                    "under it in InSilicoStudy.SubjectsRunAtOnceGiveTheSameTrialsToTheBitAsOneAtATime");
  HATTR_SKIP_UNDER_ADDRESS_SANITIZER("4 studies of 108 trials took 159 s under it (clean-clone run 27); "
                                     "StrategiesCli.PrintsOnePhaseARowAndAStrategyAColumn runs the same code under it");
  test::TempDir dir;
  const RunResult r = runHattr(dir, "sim compare-strategies --strategies basic,pcontrol,fading --hypotheses "
                                    "position-plan,guidance-dependent --subjects 3 --trials 2 --aa-seeds 1 --threads 1 "
                                    "--json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["strategies"], nlohmann::json({"basic", "pcontrol", "fading"}));
  ASSERT_EQ(j["hypotheses"].size(), 2u);
  for (const auto& h : j["hypotheses"]) {
    // groups-retention's phases in its order, transfer on the second character, then each phase
    // of the baseline's character as its change from the baseline.
    std::vector<std::string> phases;
    for (const auto& p : h["phases"]) phases.push_back(p["phase"].get<std::string>() + "/" + p["skill"].get<std::string>());
    EXPECT_EQ(phases, (std::vector<std::string>{"baseline/na", "training/na", "post-test/na", "retention/na",
                                                "transfer/loop", "training − baseline/na", "post-test − baseline/na",
                                                "retention − baseline/na"}));
    // A change is each subject's phase mean less its baseline mean, averaged: the means' difference.
    for (std::size_t s = 0; s < 3; ++s) {
      const double change = h["phases"][6]["strategies"][s]["shape"]["mean"];
      const double post = h["phases"][2]["strategies"][s]["shape"]["mean"];
      const double baseline = h["phases"][0]["strategies"][s]["shape"]["mean"];
      EXPECT_NEAR(change, post - baseline, 1e-9 * std::abs(post));
    }
    for (const auto& p : h["phases"]) {
      ASSERT_EQ(p["strategies"].size(), 3u);
      for (const auto& s : p["strategies"]) {
        EXPECT_EQ(s["shape"]["subjects"], 3) << p.dump();
        if (p["phase"].get<std::string>().find("baseline") == 0 || p["phase"].get<std::string>().find(' ') == std::string::npos) {
          EXPECT_GT(s["shape"]["mean"].get<double>(), 0.0);
        }
      }
      EXPECT_GE(p["p_shape"].get<double>(), 0.0);
      EXPECT_LE(p["p_shape"].get<double>(), 1.0);
      EXPECT_LE(p["aa"]["significant_shape"].get<int>(), 1);
    }
  }
  // The guidance-dependent learner is the position-plan learner wherever nothing guides: the
  // basic group's every phase, and every group's baseline, the same to the bit; guided training differs.
  const auto& plan = j["hypotheses"][0]["phases"];
  const auto& dependent = j["hypotheses"][1]["phases"];
  for (std::size_t i = 0; i < plan.size(); ++i) {
    EXPECT_EQ(plan[i]["strategies"][0], dependent[i]["strategies"][0]) << plan[i]["phase"];
  }
  EXPECT_EQ(plan[0]["strategies"], dependent[0]["strategies"]) << "the baseline";
  EXPECT_NE(plan[2]["strategies"][1]["shape"]["mean"], dependent[2]["strategies"][1]["shape"]["mean"])
      << "PCONTROL's post-test: the dependent learner learned less of its error while guided";
}

// The table for people, on the smallest design: one study of 2 strategies × 2 subjects × 6 trials.
TEST(StrategiesCli, PrintsOnePhaseARowAndAStrategyAColumn) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  const RunResult table = runHattr(dir, "sim compare-strategies --strategies basic,pcontrol --hypotheses position-plan "
                                        "--subjects 2 --trials 1 --aa-seeds 0 --threads 1");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_THAT(table.out, HasSubstr("position-plan, shape cost\nphase"));
  EXPECT_THAT(table.out, HasSubstr("basic      pcontrol        p  A/A\nbaseline (na)"));
  EXPECT_THAT(table.out, HasSubstr("transfer (loop)"));
  EXPECT_THAT(table.out, HasSubstr("retention − baseline (na)"));
  EXPECT_THAT(table.out, HasSubstr("position-plan, force cost"));
}

TEST(StrategiesCli, RefusesWhatCannotBeComparedWithExitTwo) {
  test::TempDir dir;
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"--strategies basic,mentor-force", "mentor-force needs a live mentor"},
           {"--strategies basic", "expected at least 2 to compare"},
           {"--strategies basic,basic", "\"basic\" is given twice"},
           {"--strategies basic,beta", "got \"beta\""},
           {"--design paper", "expected a design of groups and sessions"},
           {"--design nonesuch", "no such design"},
           {"--hypotheses position-plan,lazy", "lazy"}}) {
    const RunResult r = runHattr(dir, "sim compare-strategies --subjects 2 --trials 1 --aa-seeds 0 " + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr(message)) << args;
  }
}

}  // namespace
}  // namespace hattr
