// hattr sim compare-hypotheses on a reduced protocol: the paper's points under each learning
// hypothesis, and an A/A check each that shows what a hypothesis changes only acts through
// guidance (guidance-dependent) or also without it (force-plan's grip).

#include <map>
#include <set>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/run_command.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;
using test::RunResult;
using test::hattrCli;

/// A/A studies per hypothesis: one under the sanitizers (nine studies took 115 s under
/// AddressSanitizer), two elsewhere.
constexpr int kAaSeeds = test::kSanitized ? 1 : 2;

TEST(HypothesesCli, TabulatesThePapersPointsUnderEachHypothesisWithAnAaCheckEach) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("one thread (--threads 1) simulating and scoring 5 studies; subjects at once run "
                                    "under it in InSilicoStudy.SubjectsRunAtOnceGiveTheSameTrialsToTheBitAsOneAtATime");
  test::TempDir dir;
  const RunResult r = test::runCommand(
      dir, hattrCli(),
      fmt::format("sim compare-hypotheses --subjects 3 --trials 2 --aa-seeds {} --threads 1 --json --out {}", kAaSeeds,
                  (dir / "out").string()),
      "compare");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["hypotheses"].size(), 3u);
  std::map<std::string, nlohmann::json> by_name;
  for (const auto& h : j["hypotheses"]) {
    const std::string name = h["hypothesis"];
    by_name[name] = h;
    ASSERT_EQ(h["points"].size(), 21u) << name;
    int agrees = 0;
    int differs = 0;
    for (const auto& p : h["points"]) {
      const std::string a = p["agreement"];
      EXPECT_TRUE(a == "agrees" || a == "differs" || a == "not measured") << a;
      agrees += a == "agrees";
      differs += a == "differs";
    }
    EXPECT_EQ(h["agrees"], agrees) << name;
    EXPECT_EQ(h["differs"], differs) << name;
    ASSERT_EQ(h["aa"]["p_mode_trajectory"].size(), static_cast<std::size_t>(kAaSeeds)) << name;
  }
  const auto& plain = by_name.at("position-plan");
  const auto& dependent = by_name.at("guidance-dependent");
  const auto& force = by_name.at("force-plan");
  // Without guidance the guidance-dependent learner is the position-plan learner to the bit;
  // the force-plan learner's loose grip writes every trial differently.
  EXPECT_EQ(dependent["aa"], plain["aa"]);
  EXPECT_NE(force["aa"]["p_mode_trajectory"], plain["aa"]["p_mode_trajectory"]);
  // With guidance the three are three different studies.
  const std::set<double> p_modes{plain["p_mode_trajectory"].get<double>(), dependent["p_mode_trajectory"].get<double>(),
                                 force["p_mode_trajectory"].get<double>()};
  EXPECT_EQ(p_modes.size(), 3u);
  // Each study records its subjects' hypothesis, so it resumes under the same one.
  EXPECT_THAT(test::readText(dir / "out" / "force-plan" / "study.json"), HasSubstr("\"hypothesis\": \"force-plan\""));
}

TEST(HypothesesCli, PrintsATable) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("one thread (--threads 1) simulating and scoring a study");
  test::TempDir dir;
  const RunResult table = test::runCommand(
      dir, hattrCli(),
      "sim compare-hypotheses --hypotheses force-plan --subjects 3 --trials 2 --aa-seeds 0 --threads 1 --out " +
          (dir / "out").string(),
      "table");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_THAT(table.out, HasSubstr("force-plan"));
  EXPECT_THAT(table.out, HasSubstr("points that agree (of 21)"));
  EXPECT_THAT(table.out, HasSubstr("shape, BASIC: difference between subjects"));
}

TEST(HypothesesCli, RefusesAnUnknownHypothesisAndOneGivenTwice) {
  test::TempDir dir;
  const RunResult bad =
      test::runCommand(dir, hattrCli(), "sim compare-hypotheses --hypotheses position-plan,telepathy", "bad");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("--hypotheses: expected one of position-plan, force-plan, guidance-dependent, got "
                                 "\"telepathy\""));
  const RunResult twice =
      test::runCommand(dir, hattrCli(), "sim compare-hypotheses --hypotheses force-plan,force-plan", "twice");
  EXPECT_EQ(twice.exit_code, 2);
  EXPECT_THAT(twice.err, HasSubstr("--hypotheses: \"force-plan\" is given twice"));
}

}  // namespace
}  // namespace hattr
