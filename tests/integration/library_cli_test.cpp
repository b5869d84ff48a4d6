// hattr library end to end: the SVC2004 folder imported, the protocol's EERs recomputed here from
// the scores it wrote, identification as brute force's, a trial against a template; and bad
// input refused with exit code 2, the library unchanged.

#include <fstream>
#include <map>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "hattr/io/profile_csv.hpp"
#include "hattr/io/table_csv.hpp"
#include "library/synthetic_writers.hpp"
#include "support/run_command.hpp"
#include "support/test_support.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;
using test::runHattr;

int entryCount(const test::TempDir& dir, const std::string& lib) {
  const auto listed = runHattr(dir, "library -L " + lib + " list --json", "count");
  EXPECT_EQ(listed.exit_code, 0) << listed.err;
  return static_cast<int>(nlohmann::json::parse(listed.out)["entries"].size());
}

TEST(LibraryCli, BadInputExitsTwoAndLeavesTheLibraryAsItWas) {
  test::TempDir dir;
  const std::string lib = (dir / "lib.sqlite").string();
  auto r = runHattr(dir, "library -L " + lib + " list");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("no such profile library"));
  ASSERT_EQ(runHattr(dir, "library -L " + lib + " init").exit_code, 0);
  r = runHattr(dir, "library -L " + lib + " init");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("already exists"));

  io::writeProfileCsv(test::syntheticSignature(1, 0), dir / "a.csv");
  io::writeProfileCsv(test::syntheticSignature(1, 1), dir / "b.csv");
  ASSERT_EQ(runHattr(dir, "library -L " + lib + " add " + (dir / "a.csv").string() + " --person W1 --skill signature").exit_code, 0);
  r = runHattr(dir, "library -L " + lib + " add " + (dir / "a.csv").string() + " --person W1 --skill signature");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("entry W1/signature/a is already in the library"));
  r = runHattr(dir, "library -L " + lib + " add " + (dir / "b.csv").string() + " --person W1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("expected --person and --skill"));
  r = runHattr(dir, "library -L " + lib + " import svc2004 " + dir.path().string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("no U<writer>S<signature>.TXT file"));
  r = runHattr(dir, "library -L " + lib + " remove W1/signature/a nobody");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(entryCount(dir, lib), 1);

  // Verification: an unknown person, one recording, no threshold, a missing channel.
  r = runHattr(dir, "library -L " + lib + " verify " + (dir / "b.csv").string() + " --claim W9 --skill signature --threshold 2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("no signature profiles of W9"));
  r = runHattr(dir, "library -L " + lib + " verify " + (dir / "b.csv").string() + " --claim W1 --skill signature --threshold 2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("1 reference profile; expected at least 2"));
  ASSERT_EQ(runHattr(dir, "library -L " + lib + " add " + (dir / "b.csv").string() + " --person W1 --skill signature").exit_code, 0);
  r = runHattr(dir, "library -L " + lib + " verify " + (dir / "b.csv").string() + " --claim W1 --skill signature");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("no verification threshold"));
  io::writeProfileCsv(test::syntheticSignature(1, 2, 7, false), dir / "flat.csv");
  r = runHattr(dir, "library -L " + lib + " verify " + (dir / "flat.csv").string() +
                        " --claim W1 --skill signature --features angles --threshold 2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("needs the channel azimuth"));
  r = runHattr(dir, "library -L " + lib + " evaluate --protocol svc2004");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("no signature profiles of writer U1"));
  r = runHattr(dir, "library -L " + lib + " evaluate --protocol other");
  EXPECT_EQ(r.exit_code, 2);
  r = runHattr(dir, "train --reference library:" + lib + "#W1/na --hand " + (dir / "a.csv").string() + " -o t.csv");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("no genuine na profiles of W1"));
  EXPECT_EQ(entryCount(dir, lib), 2);

  // Export: whole, with an index; a second export refuses the folder.
  ASSERT_EQ(runHattr(dir, "library -L " + lib + " export -o " + (dir / "out").string()).exit_code, 0);
  EXPECT_EQ(io::readTable(dir / "out" / "library.csv").rows.size(), 2u);
  EXPECT_EQ(io::readProfileCsv(dir / "out" / "profiles" / "00001.csv").metadata().extra.at("library_person"), "W1");
  EXPECT_EQ(runHattr(dir, "library -L " + lib + " export -o " + (dir / "out").string()).exit_code, 2);
}

/// The a-posteriori EER, recomputed from scores: every threshold halfway between two distinct
/// scores (and below all), FAR and FRR counted, the least |FAR - FRR|.
double eerOf(const std::vector<double>& genuine, const std::vector<double>& impostor) {
  std::vector<double> all(genuine);
  all.insert(all.end(), impostor.begin(), impostor.end());
  std::sort(all.begin(), all.end());
  double best_gap = 2.0, eer = 1.0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const double t = all[i];  // accept score <= t
    double fa = 0, fr = 0;
    for (const double s : impostor) fa += s <= t ? 1 : 0;
    for (const double s : genuine) fr += s > t ? 1 : 0;
    fa /= static_cast<double>(impostor.size());
    fr /= static_cast<double>(genuine.size());
    if (std::abs(fa - fr) < best_gap) best_gap = std::abs(fa - fr), eer = (fa + fr) / 2;
  }
  return eer;
}

TEST(LibraryCli, Svc2004EvaluationsEersAreTheScoresOwnAndIdentificationIsExact) {
  const auto folder = test::svc2004Folder();
  if (!folder) GTEST_SKIP() << "SVC2004 data not found at ../shared/data/svc2004-task2 beside the project";
  test::TempDir dir;
  const std::string lib = (dir / "svc.sqlite").string();
  auto r = runHattr(dir, "library -L " + lib + " import svc2004 " + folder->string() + " --json", "import");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["count"], 1600);
  // A second import adds nothing.
  r = runHattr(dir, "library -L " + lib + " import svc2004 " + folder->string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("svc2004/U1S1 is already in the library"));

  r = runHattr(dir, "library -L " + lib + " evaluate --protocol svc2004 --runs 3 --sets shape,shape+force,all "
                    "--save-thresholds --json -o " + (dir / "report").string(), "evaluate");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto json = nlohmann::json::parse(r.out);
  // Recompute each split's EERs from scores.csv.
  const io::Table scores = io::readTable(dir / "report" / "scores.csv");
  std::map<std::string, std::map<std::string, std::vector<double>>> by;  // split|set -> kind -> scores
  const auto split = scores.text("split"), set = scores.text("features"), kind = scores.text("kind");
  const auto value = scores.numbers("score");
  for (std::size_t i = 0; i < value.size(); ++i) by[split[i] + "|" + set[i]][kind[i]].push_back(value[i]);
  int checked = 0;
  for (const auto& s : json["sets"]) {
    for (const auto& [name, sp] : s["splits"].items()) {
      auto& k = by[name + "|" + s["features"].get<std::string>()];
      EXPECT_EQ(k["genuine"].size(), sp["skilled"]["genuine_scores"].get<std::size_t>());
      EXPECT_NEAR(eerOf(k["genuine"], k["skilled"]), sp["skilled"]["eer_a_posteriori"].get<double>(), 1e-12);
      EXPECT_NEAR(eerOf(k["genuine"], k["random"]), sp["random"]["eer_a_posteriori"].get<double>(), 1e-12);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 9);
  // Writers 1-20 for choices, 21-40 for the report, both named.
  EXPECT_EQ(json["options"]["development"].size(), 20u);
  EXPECT_EQ(json["options"]["evaluation"].front(), "U21");
  const std::string html = test::readText(dir / "report" / "report.html");
  EXPECT_THAT(html, HasSubstr("id=\"det_shape-force_evaluation\""));
  EXPECT_THAT(html, HasSubstr("a-priori"));

  // Identification with the bounds: brute force's ranks.
  for (const std::string probe : {"svc2004/U5S15", "svc2004/U33S12", "svc2004/U12S23"}) {
    const std::string args = "library -L " + lib + " identify entry:" + probe + " --skill signature --top 5 --json";
    const auto fast = runHattr(dir, args, "fast");
    const auto brute = runHattr(dir, args + " --brute-force", "brute");
    ASSERT_EQ(fast.exit_code, 0) << fast.err;
    EXPECT_EQ(nlohmann::json::parse(fast.out)["ranked"], nlohmann::json::parse(brute.out)["ranked"]) << probe;
  }
  // Verification with the saved threshold: a second-session signature as its writer.
  r = runHattr(dir, "library -L " + lib + " verify entry:svc2004/U30S15 --claim U30 --skill signature --session 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto v = nlohmann::json::parse(r.out);
  EXPECT_THAT(v["threshold_from"].get<std::string>(), HasSubstr("development writers"));
  EXPECT_EQ(v["references"], 10);
  EXPECT_EQ(v["accepted"].get<bool>(), v["score"].get<double>() <= v["threshold"].get<double>());

  // A trial against a writer's template.
  r = runHattr(dir, "library -L " + lib + " template --person U3 --skill signature -o " + (dir / "u3.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = runHattr(dir, "train --reference library:" + lib + "#U3/signature --hand " + (dir / "u3.csv").string() +
                        " --mode alpha -o " + (dir / "trial.csv").string(), "train");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const HapticProfile trial = io::readProfileCsv(dir / "trial.csv");
  EXPECT_GT(trial.duration_s(), 1.0);
  EXPECT_EQ(trial.metadata().extra.at("reference"), "library:" + lib + "#U3/signature");
}

}  // namespace
}  // namespace hattr
