// `hattr learner plan | list | progress` (issue 39): a practice plan made, listed and its
// progress page written from the command line, and bad input refused with exit code 2.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "support/run_command.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;

TEST(LearnerCli, APlanIsMadeListedAndItsProgressPagePrinted) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  const std::string folder = (dir / "practice").string();
  const auto made = test::runCommand(dir, test::hattrCli(),
                                     "learner plan --folder " + folder + " --code mia --name Mia --age 7 --letters a,7 "
                                     "--strategy alpha --sessions 2 --trials 3 --checks 1 --retention-days 0",
                                     "plan");
  ASSERT_EQ(made.exit_code, 0) << made.err;
  // Session 1: (1 before practice + 3 guided + 1 alone) × 2 letters; session 2: (3 + 1) × 2.
  EXPECT_THAT(made.out, HasSubstr("mia/plan-1.sqlite: 18 trials planned over 2 sessions"));
  const auto listed = test::runCommand(dir, test::hattrCli(), "learner list --json --folder " + folder, "list");
  ASSERT_EQ(listed.exit_code, 0) << listed.err;
  const auto plans = nlohmann::json::parse(listed.out)["plans"];
  ASSERT_EQ(plans.size(), 1u);
  EXPECT_EQ(plans[0]["letters"], nlohmann::json({"a", "7"}));
  EXPECT_EQ(plans[0]["strategy"], "alpha");
  EXPECT_EQ(plans[0]["plain_strategy"], "Guided pressure");
  const std::string db = folder + "/mia/plan-1.sqlite";
  const std::string page = (dir / "page.html").string();
  const auto progress = test::runCommand(dir, test::hattrCli(), "learner progress --db " + db + " --html " + page, "progress");
  ASSERT_EQ(progress.exit_code, 0) << progress.err;
  EXPECT_THAT(progress.out, HasSubstr("Session 1: not begun yet.\nSession 2: not begun yet.\nnext: session 1 of 2"));
  EXPECT_THAT(test::readText(page), HasSubstr("Progress of Mia (mia)"));
  // The page is not replaced without --force; pseudonymized, the name is left out.
  const auto again = test::runCommand(dir, test::hattrCli(), "learner progress --db " + db + " --html " + page, "again");
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_THAT(again.err, HasSubstr("already exists"));
  const auto plain = test::runCommand(dir, test::hattrCli(),
                                      "learner progress --db " + db + " --html " + page + " --force --pseudonymized", "plain");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_THAT(test::readText(page), HasSubstr("Progress of learner mia"));
}

TEST(LearnerCli, ABadPlanIsRefusedWithEveryProblem) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  const auto bad = test::runCommand(dir, test::hattrCli(),
                                    "learner plan --folder " + (dir / "p").string() +
                                        " --code 'a b' --letters zz --handedness up --sessions 0",
                                    "bad");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("practice plan: 4 problems:"));
  EXPECT_THAT(bad.err, HasSubstr("letters: \"zz\": not a letter of the library or a glyph file"));
  const auto missing = test::runCommand(dir, test::hattrCli(), "learner list --folder " + (dir / "nowhere").string(), "list");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_THAT(missing.err, HasSubstr("nowhere: expected a folder, got nothing there"));
}

}  // namespace
}  // namespace hattr
