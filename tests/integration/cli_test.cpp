// Runs the hattr command-line tool as a user would and checks exit codes and messages.

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <sstream>

#include <fmt/format.h>

#include <algorithm>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "hattr/io/profile_csv.hpp"
#include "support/run_command.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;
using test::RunResult;
using test::runHattr;

constexpr const char* kGoodProfile =
    "# subject: S1\n# skill: na\n# rate_hz: 100\n"
    "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n"
    "0,0.001,0.002,0,0,0,-1.5,1\n0.01,0.002,0.002,0,0,0,-2,1\n0.02,0.003,0.001,0,0,0,0,0\n";

TEST(Cli, VersionAndHelpExitZero) {
  test::TempDir dir;
  const RunResult version = runHattr(dir, "--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_THAT(version.out, HasSubstr("hattr 0."));
  for (const char* sub : {"--help", "profile --help", "profile info --help", "profile convert --help",
                          "import --help", "import svc2004 --help", "import susig --help", "demo --help"}) {
    const RunResult help = runHattr(dir, sub);
    EXPECT_EQ(help.exit_code, 0) << sub;
    EXPECT_THAT(help.out, HasSubstr("Usage")) << sub;
  }
}

// Issue 39: every built-in glyph, one a line, name first; the JSON its numbers.
TEST(Cli, SimGlyphsListsEveryBuiltInGlyph) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  const RunResult text = runHattr(dir, "sim glyphs");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_THAT(text.out, HasSubstr("capital-a    A         U+0041         3    13.0×20.0        50.5\n"));
  EXPECT_THAT(text.out, HasSubstr("\nna           ந         U+0BA8         3"));
  const RunResult r = runHattr(dir, "sim glyphs --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto glyphs = nlohmann::json::parse(r.out)["glyphs"];
  ASSERT_EQ(glyphs.size(), 64u);
  const auto small_g = std::find_if(glyphs.begin(), glyphs.end(), [](const auto& g) { return g["name"] == "small-g"; });
  ASSERT_NE(small_g, glyphs.end());
  EXPECT_EQ((*small_g)["character"], "g");
  EXPECT_EQ((*small_g)["strokes"], 1);
  EXPECT_NEAR((*small_g)["height_mm"].get<double>(), 17.0, 1e-9);  // midline 0 to the descender line -17
}

TEST(Cli, ProfileInfoJsonHasTheStableKeys) {
  test::TempDir dir;
  test::writeText(dir / "p.csv", kGoodProfile);
  const RunResult r = runHattr(dir, "profile info --json " + (dir / "p.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["samples"].get<int>(), 3);
  EXPECT_DOUBLE_EQ(json["duration_s"].get<double>(), 0.02);
  EXPECT_NEAR(json["rate_hz"].get<double>(), 100.0, 1e-9);
  EXPECT_DOUBLE_EQ(json["channels"]["fz"]["min"].get<double>(), -2.0);
  EXPECT_EQ(json["channels"]["fz"]["unit"], "N");
  EXPECT_EQ(json["metadata"]["subject"], "S1");
  EXPECT_EQ(json["pen_down_samples"].get<int>(), 2);
}

TEST(Cli, BadInputExitsTwoWithTheLineInTheMessage) {
  test::TempDir dir;
  const std::string base = "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,0,1\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "empty file"},
      {base + "0.1,0,0,0,0,0,1\n", "bad.csv:3: expected 8 fields, got 7"},
      {base + "0.1,0,0,0,0,0,x,1\n", "bad.csv:3: column 7 (fz_N): expected a number"},
      {base + "0.1,0,0,0,0,0,inf,1\n", "bad.csv:3: column 7 (fz_N): expected a finite number"},
      {base + "0,0,0,0,0,0,0,1\n", "bad.csv:3: column 1 (t_s): time must increase strictly"},
      {"t_s,x_m,y_m,z_m,fx_N,fy_N,pen_down_bool\n", "bad.csv:1: missing required column(s): fz"},
      {"t_s,x_furlong,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n", "bad.csv:1: column 2 (x_furlong): unknown unit"},
  };
  for (const auto& [text, message] : cases) {
    test::writeText(dir / "bad.csv", text);
    const RunResult r = runHattr(dir, "profile info " + (dir / "bad.csv").string());
    EXPECT_EQ(r.exit_code, 2) << message;
    EXPECT_THAT(r.err, HasSubstr(message));
  }
}

TEST(Cli, UsageErrorsExitTwo) {
  test::TempDir dir;
  EXPECT_EQ(runHattr(dir, "").exit_code, 2);
  EXPECT_EQ(runHattr(dir, "profile info").exit_code, 2);
  EXPECT_EQ(runHattr(dir, "frobnicate").exit_code, 2);
  const RunResult missing = runHattr(dir, "profile info " + (dir / "none.csv").string());
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_THAT(missing.err, HasSubstr("none.csv: cannot open for reading"));
}

TEST(Cli, ConvertRefusesToOverwriteAndKeepsTheExistingFile) {
  test::TempDir dir;
  test::writeText(dir / "in.csv", kGoodProfile);
  test::writeText(dir / "out.csv", "precious");
  const RunResult r = runHattr(dir, "profile convert " + (dir / "in.csv").string() + " " + (dir / "out.csv").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("already exists; add --force to replace it"));
  EXPECT_EQ(test::readText(dir / "out.csv"), "precious");
  const RunResult forced =
      runHattr(dir, "profile convert --force " + (dir / "in.csv").string() + " " + (dir / "out.csv").string());
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_EQ(io::readProfileCsv(dir / "out.csv").size(), 3u);
}

TEST(Cli, ImportSvc2004ThenInfoGivesDurationAndPointCount) {
  const auto folder = test::svc2004Folder();
  if (!folder) GTEST_SKIP() << "SVC2004 data not found at ../shared/data/svc2004-task2 beside the project";
  test::TempDir dir;
  const std::string out = (dir / "u1s1.csv").string();
  const RunResult imported = runHattr(dir, "import svc2004 " + (*folder / "U1S1.TXT").string() + " -o " + out);
  ASSERT_EQ(imported.exit_code, 0) << imported.err;
  const RunResult info = runHattr(dir, "profile info --json " + out);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto json = nlohmann::json::parse(info.out);
  // U1S1.TXT: 84 points from T = 31275775 ms to 31276987 ms, and 5 lifts (points with button 0
  // after a gap), each marked by one pen-up sample (read off the file).
  EXPECT_EQ(json["samples"].get<int>(), 84 + 5);
  EXPECT_NEAR(json["duration_s"].get<double>(), 1.212, 1e-9);
  EXPECT_EQ(json["metadata"]["source"], "import:svc2004 U1S1.TXT");
}

TEST(Cli, ImportOfAMalformedRecordingExitsTwo) {
  test::TempDir dir;
  test::writeText(dir / "bad.TXT", "2\n1 2 3 1 0 900 5\n");
  const RunResult r = runHattr(dir, "import svc2004 " + (dir / "bad.TXT").string() + " -o " + (dir / "o.csv").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("bad.TXT: line 1 announces 2 points, the file has 1"));
  EXPECT_FALSE(std::filesystem::exists(dir / "o.csv"));
}

TEST(Cli, ServoCheckJsonHasTheStableKeys) {
  test::TempDir dir;
  const RunResult r = runHattr(dir, "servo-check --rate 1000 --seconds 0.2 --realtime skip --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto json = nlohmann::json::parse(r.out);
  for (const char* part : {"loop", "floor"}) {
    for (const char* key : {"p50", "p99", "p99_9", "max"}) {
      EXPECT_TRUE(json[part]["period_error_us"][key].is_number()) << part << "." << key;
    }
  }
  for (const char* key : {"p50", "p99", "p99_9", "max"}) EXPECT_TRUE(json["loop"]["tick_compute_us"][key].is_number());
  // How many ticks fit in 0.2 s is the host's business (a loaded host holds the loop up); every
  // tick's sample is either consumed or counted as dropped.
  const auto& loop = json["loop"];
  EXPECT_GT(loop["ticks"].get<int>(), 0) << r.out;
  EXPECT_EQ(loop["samples_consumed"].get<int>() + loop["dropped_samples"].get<int>(), loop["ticks"].get<int>()) << r.out;
  EXPECT_EQ(loop["faults"].get<int>(), 0) << r.out;
  EXPECT_TRUE(json["loop"]["overruns"].is_number());
  EXPECT_TRUE(json["loop"]["dropped_samples"].is_number());
  EXPECT_TRUE(json["ratio_p99"].is_number());
}

TEST(Cli, ServoCheckRejectsABadDeviceWithExitTwo) {
  test::TempDir dir;
  const RunResult r = runHattr(dir, "servo-check --seconds 0.1 --realtime skip --device usb://x");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("unknown scheme \"usb\"; accepted: sim://pen"));
  EXPECT_EQ(runHattr(dir, "servo-check --rate 20000").exit_code, 2);
}

// A value nested 100 000 deep crashed the error path (printed recursively); a huge value made a
// huge message. Every JSON file goes through one reader that bounds both.
TEST(Cli, DeeplyNestedOrHugeJsonValuesAreRefusedWithAShortMessage) {
  test::TempDir dir;
  const std::string deep = std::string(100'000, '[') + std::string(100'000, ']');
  test::writeText(dir / "deep-study.json", R"({"name": "x", "skill": "na", "experts": {"na": )" + deep + "}}");
  test::writeText(dir / "deep-world.json", R"({"paper": )" + deep + "}");
  for (const std::string& command : {"study init " + (dir / "deep-study.json").string() + " --db " + (dir / "d.sqlite").string(),
                                    "world check " + (dir / "deep-world.json").string()}) {
    const RunResult r = runHattr(dir, command);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr("JSON nested deeper than 64 levels")) << command;
  }
  std::string huge = "[0";
  for (int i = 1; i < 20'000; ++i) huge += ", " + std::to_string(i);
  huge += "]";
  test::writeText(dir / "huge.json", R"({"paper": {"stiffness_N_per_m": )" + huge + "}}");
  const RunResult r = runHattr(dir, "world check " + (dir / "huge.json").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("key paper.stiffness_N_per_m: expected a number"));
  EXPECT_THAT(r.err, HasSubstr("characters)"));
  EXPECT_LT(r.err.size(), 400u) << r.err.substr(0, 400);
}

TEST(Cli, WorldCheckReportsClampsAndRefusesBadConfigs) {
  test::TempDir dir;
  test::writeText(dir / "stiff.json", R"({"paper": {"stiffness_N_per_m": 4000}, "relief": {"kind": "flat"}})");
  const RunResult ok = runHattr(dir, "world check --json " + (dir / "stiff.json").string());
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  const auto json = nlohmann::json::parse(ok.out);
  ASSERT_FALSE(json["clamps"].empty());
  EXPECT_THAT(json["clamps"][0].get<std::string>(), HasSubstr("paper stiffness 4000 N/m -> 1000 N/m: device maximum stiffness"));

  test::writeText(dir / "bad.json", R"({"friction": {"static": 3}})");
  const RunResult bad = runHattr(dir, "world check " + (dir / "bad.json").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("bad.json: key friction.static: expected a number in [0, 2], got 3"));

  const RunResult defaults = runHattr(dir, "world defaults");
  ASSERT_EQ(defaults.exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(defaults.out)["writing_angle_deg"].get<double>(), 60.0);
}

/// A hand script in millimetres: a loop over 1 s, pressing 1.2 N.
std::string handScript(double y_offset_mm = 0.0, double press_N = 1.2) {
  std::string text = "# skill: loop\nt_s,x_mm,y_mm,z_mm,fx_N,fy_N,fz_N,pen_down_bool\n";
  for (int i = 0; i <= 100; ++i) {
    const double t = i * 0.01, a = 6.0 * t;
    text += fmt::format("{},{},{},0,0,0,{},1\n", t, 20 * std::sin(a), 10 * std::sin(2 * a) + y_offset_mm * t, -press_N);
  }
  return text;
}

// A hand that presses 20 N where the pen renders 1.75 N sinks through the paper: the recording
// is written and marked, and the command exits 1 naming what happened, unless told to keep it
// (issue 38).
TEST(Cli, ARecordingThroughThePaperIsKeptMarkedAndFailsUnlessKeepDisturbed) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "heavy.csv", handScript(0.0, 20.0));
  const auto path = [&](const char* name) { return (dir / name).string(); };
  const RunResult refused = runHattr(dir, "record --hand " + path("heavy.csv") + " -o " + path("heavy_out.csv"));
  EXPECT_EQ(refused.exit_code, 1) << refused.err;
  EXPECT_THAT(refused.err, HasSubstr("the trial was disturbed: "));
  EXPECT_THAT(refused.err, HasSubstr("mm under the paper at "));
  EXPECT_THAT(refused.err, HasSubstr("--keep-disturbed"));
  const HapticProfile kept = io::readProfileCsv(path("heavy_out.csv"));
  EXPECT_THAT(kept.metadata().extra.at("disturbed"), HasSubstr("under the paper"));
  EXPECT_EQ(kept.metadata().extra.count("physical_penetration"), 1u);

  const RunResult accepted = runHattr(dir, "record --hand " + path("heavy.csv") + " -o " + path("kept.csv") +
                                               " --keep-disturbed --json");
  ASSERT_EQ(accepted.exit_code, 0) << accepted.err;
  const auto json = nlohmann::json::parse(accepted.out);
  EXPECT_GE(json["physical_events"]["penetration"]["count"].get<int>(), 1);
  EXPECT_GT(json["physical_events"]["penetration"]["deepest_m"].get<double>(), 0.003);
  EXPECT_THAT(json["disturbed"].get<std::string>(), HasSubstr("under the paper"));

  test::writeText(dir / "light.csv", handScript());
  const RunResult clean = runHattr(dir, "record --hand " + path("light.csv") + " -o " + path("light_out.csv") + " --json");
  ASSERT_EQ(clean.exit_code, 0) << clean.err;
  EXPECT_EQ(nlohmann::json::parse(clean.out)["disturbed"], "");
}

// Issue 38: train refuses a reference (or a hand) the pen cannot render, before the trial, with
// the numbers and the remedy; `profile convert --scale-force` is that remedy.
TEST(Cli, TrainRefusesAReferenceThePenCannotRenderAndScalingItsForcesFixesIt) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "heavy.csv", handScript(0.0, 3.5));
  test::writeText(dir / "light.csv", handScript());
  const auto path = [&](const char* name) { return (dir / name).string(); };
  const RunResult refused = runHattr(dir, "train --mode alpha --reference " + path("heavy.csv") + " --hand " +
                                              path("light.csv") + " -o " + path("out.csv"));
  EXPECT_EQ(refused.exit_code, 2) << refused.err;
  EXPECT_THAT(refused.err, HasSubstr("--reference " + path("heavy.csv") + ": it presses up to 3.50 N"));
  EXPECT_THAT(refused.err, HasSubstr("--scale-force 0.5"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out.csv"));

  const RunResult scaled = runHattr(dir, "profile convert " + path("heavy.csv") + " " + path("scaled.csv") + " --scale-force 0.5");
  ASSERT_EQ(scaled.exit_code, 0) << scaled.err;
  EXPECT_THAT(scaled.out, HasSubstr("forces scaled by 0.5"));
  const HapticProfile halved = io::readProfileCsv(path("scaled.csv"));
  EXPECT_NEAR(halved.range(Channel::kFz).min, -1.75, 1e-9);
  EXPECT_EQ(halved.metadata().extra.at("force_scaled_by"), "0.5");
  const RunResult trained = runHattr(dir, "train --mode alpha --reference " + path("scaled.csv") + " --hand " +
                                              path("light.csv") + " -o " + path("out.csv"));
  EXPECT_EQ(trained.exit_code, 0) << trained.err;

  // A reference that fits the workspace but lies outside it (drifting 75 mm up in y over its
  // second): refused with `--centre` as the remedy, which places it on the paper.
  test::writeText(dir / "far.csv", handScript(75.0));
  const RunResult far = runHattr(dir, "train --mode alpha --reference " + path("far.csv") + " --hand " +
                                          path("light.csv") + " -o " + path("far_out.csv"));
  EXPECT_EQ(far.exit_code, 2) << far.err;
  EXPECT_THAT(far.err, HasSubstr("outside the device's workspace of -60.0 to 60.0 mm"));
  EXPECT_THAT(far.err, HasSubstr("hattr profile convert IN OUT --centre"));
  const RunResult centred = runHattr(dir, "profile convert " + path("far.csv") + " " + path("centred.csv") + " --centre");
  ASSERT_EQ(centred.exit_code, 0) << centred.err;
  EXPECT_THAT(centred.out, HasSubstr("centred on the paper: placed_shift_m"));
  const HapticProfile placed = io::readProfileCsv(path("centred.csv"));
  EXPECT_NEAR(placed.range(Channel::kY).min + placed.range(Channel::kY).max, 0.0, 1e-9);
  const RunResult fits = runHattr(dir, "train --mode alpha --reference " + path("centred.csv") + " --hand " +
                                           path("light.csv") + " -o " + path("far_out.csv"));
  EXPECT_EQ(fits.exit_code, 0) << fits.err;
}

TEST(Cli, RecordThenTrainInEveryModeWritesProfilesWithGuidanceApart) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "script.csv", handScript());
  test::writeText(dir / "drift.csv", handScript(5.0));
  const auto path = [&](const char* name) { return (dir / name).string(); };
  const RunResult rec = runHattr(dir, "record --hand " + path("script.csv") + " -o " + path("expert.csv") + " --world " +
                                          path("flat.json"));
  EXPECT_EQ(rec.exit_code, 2) << "the world file does not exist yet";
  test::writeText(dir / "flat.json", R"({"relief": {"kind": "flat"}})");
  const RunResult recorded = runHattr(dir, "record --hand " + path("script.csv") + " -o " + path("expert.csv") +
                                               " --world " + path("flat.json") + " --json");
  ASSERT_EQ(recorded.exit_code, 0) << recorded.err;
  EXPECT_EQ(nlohmann::json::parse(recorded.out)["metadata"]["mode"], "BASIC");

  for (const char* mode : {"basic", "pcontrol", "alpha"}) {
    const std::string out = path((std::string("trial_") + mode + ".csv").c_str());
    const RunResult r = runHattr(dir, std::string("train --mode ") + mode + " --reference " + path("expert.csv") +
                                          " --hand " + path("drift.csv") + " --world " + path("flat.json") + " -o " + out +
                                          " --indexing progress --json");
    ASSERT_EQ(r.exit_code, 0) << mode << ": " << r.err;
    const auto json = nlohmann::json::parse(r.out);
    EXPECT_EQ(json["metadata"]["indexing"], "progress");
    const HapticProfile trial = io::readProfileCsv(out);
    double guide = 0.0;
    for (const Sample& s : trial.samples()) guide = std::max(guide, s.f_guide_W.norm());
    if (std::string(mode) == "basic") {
      EXPECT_EQ(guide, 0.0);
    } else {
      EXPECT_GT(guide, 0.05) << mode;
      EXPECT_FALSE(json["clamps"].empty()) << mode << ": the paper's gains exceed the default pen";
    }
  }
}

// A scheduled strategy's law has gains of its own: STRATEGY.KEY sets them, as a study file's
// strategy_parameters does; the trial plays them (the metadata's after-clamp values).
TEST(Cli, TrainSetsAScheduledStrategysLawGainsByTheLawsName) {
  test::TempDir dir;
  test::writeText(dir / "script.csv", handScript());
  const auto path = [&](const char* name) { return (dir / name).string(); };
  ASSERT_EQ(runHattr(dir, "record --hand " + path("script.csv") + " -o " + path("expert.csv")).exit_code, 0);
  const RunResult r = runHattr(dir, "train --mode fading --param pcontrol.kp_N_per_mm=0.2 --param start_gain=0.5 "
                                    "--reference " + path("expert.csv") + " --hand " + path("script.csv") + " -o " +
                                    path("fading.csv") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto metadata = nlohmann::json::parse(r.out)["metadata"];
  EXPECT_EQ(metadata["pcontrol.kp_N_per_mm"], "0.2");
  EXPECT_EQ(metadata["pcontrol_kp_N_per_m"], "200");
  EXPECT_EQ(metadata["fading.start_gain"], "0.5");
  EXPECT_EQ(metadata["guidance_gain"], "0.5");
  // A strategy or a law parameter that is not there is refused, naming it.
  const RunResult unknown = runHattr(dir, "train --mode fading --param pcontrol.kp=1 --reference " + path("expert.csv") +
                                              " --hand " + path("script.csv") + " -o " + path("x.csv"));
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_THAT(unknown.err, HasSubstr("kp_N_per_mm"));
  const RunResult no_strategy = runHattr(dir, "train --mode fading --param beta.kp=1 --reference " + path("expert.csv") +
                                                  " --hand " + path("script.csv") + " -o " + path("y.csv"));
  EXPECT_EQ(no_strategy.exit_code, 2);
  EXPECT_THAT(no_strategy.err, HasSubstr("parameter \"beta.kp=1\": the strategy before the dot"));
  EXPECT_THAT(no_strategy.err, HasSubstr("\"beta\""));
  // The mode's own prefix is its own parameter (given twice is refused); a strategy that plays no
  // other's law takes no other's parameters.
  const RunResult twice = runHattr(dir, "train --mode fading --param start_gain=0.5 --param fading.start_gain=0.6 "
                                        "--reference " + path("expert.csv") + " --hand " + path("script.csv") + " -o " +
                                        path("z.csv"));
  EXPECT_EQ(twice.exit_code, 2);
  EXPECT_THAT(twice.err, HasSubstr("start_gain: given twice"));
  const RunResult not_scheduled = runHattr(dir, "train --mode channel --param pcontrol.kp_N_per_mm=0.2 --reference " +
                                                    path("expert.csv") + " --hand " + path("script.csv") + " -o " +
                                                    path("w.csv"));
  EXPECT_EQ(not_scheduled.exit_code, 2);
  EXPECT_THAT(not_scheduled.err, HasSubstr("channel plays no other strategy's law"));
}

TEST(Cli, TrainRefusesBadModesAndMissingFilesWithExitTwo) {
  test::TempDir dir;
  test::writeText(dir / "script.csv", handScript());
  const std::string script = (dir / "script.csv").string();
  const RunResult bad_mode =
      runHattr(dir, "train --mode beta --reference " + script + " --hand " + script + " -o " + (dir / "o.csv").string());
  EXPECT_EQ(bad_mode.exit_code, 2);
  EXPECT_THAT(bad_mode.err, HasSubstr("mode: expected one of basic, pcontrol, alpha, "));
  EXPECT_THAT(bad_mode.err, HasSubstr("got \"beta\""));
  const RunResult missing = runHattr(dir, "train --mode alpha --reference " + (dir / "none.csv").string() + " --hand " +
                                              script + " -o " + (dir / "o.csv").string());
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_THAT(missing.err, HasSubstr("none.csv: cannot open for reading"));
  EXPECT_FALSE(std::filesystem::exists(dir / "o.csv"));
}

TEST(Cli, StudyCommandsReportStatusAndRefuseBadInputWithExitTwo) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "expert.csv", handScript());
  test::writeText(dir / "bad.json", R"({"name": "x", "skill": "loop", "experts": {"loop": "nope.csv"},
      "modes": ["basic", "omega"], "subjects": {"count": 2}})");
  const RunResult bad = runHattr(dir, "study init " + (dir / "bad.json").string() + " --db " + (dir / "s.sqlite").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("2 problems in the study definition"));
  EXPECT_THAT(bad.err, HasSubstr("nope.csv\" not found"));
  EXPECT_THAT(bad.err, HasSubstr("got \"omega\""));
  EXPECT_FALSE(std::filesystem::exists(dir / "s.sqlite"));

  test::writeText(dir / "study.json", R"({"name": "cli", "skill": "loop", "experts": {"loop": "expert.csv"},
      "protocol": {"training_trials": 1, "recall_trials": 1, "tail_s": 0.05}, "world": {"relief": {"kind": "flat"}},
      "subjects": {"count": 2, "participant": "script"}})");
  const std::string db = (dir / "s.sqlite").string();
  ASSERT_EQ(runHattr(dir, "study init " + (dir / "study.json").string() + " --db " + db).exit_code, 0);
  ASSERT_EQ(runHattr(dir, "study run --quiet --subject S01 --db " + db).exit_code, 0);
  const RunResult status = runHattr(dir, "study status --json --db " + db);
  ASSERT_EQ(status.exit_code, 0) << status.err;
  const auto json = nlohmann::json::parse(status.out);
  EXPECT_EQ(json["trials_total"].get<int>(), 12);
  EXPECT_EQ(json["trials_completed"].get<int>(), 6);
  EXPECT_EQ(json["trials_interrupted"].get<int>(), 0);
  ASSERT_EQ(json["subjects"].size(), 2u);
  EXPECT_TRUE(json["subjects"][0]["next"].is_null());
  EXPECT_EQ(json["subjects"][1]["next"]["sequence"].get<int>(), 0);

  EXPECT_EQ(runHattr(dir, "study init " + (dir / "study.json").string() + " --db " + db).exit_code, 2);
  const RunResult unknown = runHattr(dir, "study run --subject S99 --db " + db);
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_THAT(unknown.err, HasSubstr("--subject S99: no such subject"));
  const RunResult not_db = runHattr(dir, "study status --db " + (dir / "study.json").string());
  EXPECT_EQ(not_db.exit_code, 2);
  EXPECT_THAT(not_db.err, HasSubstr("not a hattr study database"));
}

// Issue 35: `--glyph` takes a glyph file by its path (it looked for data/glyphs/a.json.json), a
// built-in name or the character; the expert's skill is the glyph's name.
TEST(Cli, SimExpertTakesAGlyphByItsPathOrItsCharacter) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "a.json", R"({"format": "hattr-glyph", "version": 1, "name": "hook",
      "strokes": [{"points": [[-5, 0], [0, 5], [5, 0]]}]})");
  const auto path = [&](const char* name) { return (dir / name).string(); };
  const RunResult by_path = runHattr(dir, "sim expert --glyph " + path("a.json") + " -o " + path("hook.csv"));
  ASSERT_EQ(by_path.exit_code, 0) << by_path.err;
  EXPECT_EQ(io::readProfileCsv(path("hook.csv")).metadata().skill, "hook");
  const RunResult by_character = runHattr(dir, "sim expert --glyph ந -o " + path("na.csv"));
  ASSERT_EQ(by_character.exit_code, 0) << by_character.err;
  EXPECT_EQ(io::readProfileCsv(path("na.csv")).metadata().skill, "na");
  const RunResult unknown = runHattr(dir, "sim expert --glyph zeta -o " + path("z.csv"));
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_THAT(unknown.err, HasSubstr("expected a glyph file or one of: loop, na (ந)"));
}

TEST(Cli, StudyInitRefusesABadTrialEndWithExitTwo) {
  test::TempDir dir;
  test::writeText(dir / "expert.csv", handScript());
  test::writeText(dir / "study.json", R"({"name": "cli", "skill": "loop", "experts": {"loop": "expert.csv"},
      "protocol": {"trial_end": {"pen_up_s": -1, "max_s": 0}}, "subjects": {"count": 1}})");
  const RunResult r = runHattr(dir, "study init " + (dir / "study.json").string() + " --db " + (dir / "s.sqlite").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("protocol.trial_end.pen_up_s: expected a number in [0.05, 60], got -1"));
  EXPECT_FALSE(std::filesystem::exists(dir / "s.sqlite"));
}

TEST(Cli, StudyReportSetsThePaperBesideTheStudyAndHattrDtwScoresItsTrialsAlike) {
  test::TempDir dir;
  test::writeText(dir / "expert.csv", handScript());
  // The paper's skill (by its name) in the paper's modes: a study set beside the paper.
  test::writeText(dir / "study.json", R"({"name": "cli", "skill": "na", "experts": {"na": "expert.csv"},
      "protocol": {"training_trials": 1, "recall_trials": 3, "rest_s": 0}, "world": {"relief": {"kind": "flat"}},
      "subjects": {"count": 3, "participant": "script", "options": {"jitter_mm": 2.0}}})");
  const std::string db = (dir / "s.sqlite").string();
  ASSERT_EQ(runHattr(dir, "study init " + (dir / "study.json").string() + " --db " + db).exit_code, 0);
  ASSERT_EQ(runHattr(dir, "study run --quiet --db " + db).exit_code, 0);

  // The report prints the paper's findings beside the study's, and the protocol's differences.
  const RunResult report = runHattr(dir, "study report --db " + db + " --out " + (dir / "report").string());
  ASSERT_EQ(report.exit_code, 0) << report.err;
  EXPECT_THAT(report.out, HasSubstr("The paper next to this study: "));
  EXPECT_THAT(report.out, HasSubstr("protocol differs from the paper's: 3 subjects (the paper: 10)"));
  EXPECT_THAT(report.out, HasSubstr("shape: subjects whose best mode it is — Table 1"));
  EXPECT_THAT(report.out, HasSubstr("paper: BASIC 2, PCONTROL 1, ALPHA 7 of 10"));
  EXPECT_THAT(test::readText(dir / "report" / "report.md"), HasSubstr("## The paper next to this study"));

  // hattr dtw --score on an exported trial gives the analysis's costs for it, to 1e-12.
  const RunResult analyzed = runHattr(dir, "study analyze --json --db " + db);
  ASSERT_EQ(analyzed.exit_code, 0) << analyzed.err;
  const auto costs = nlohmann::json::parse(analyzed.out)["recall_costs"];
  ASSERT_FALSE(costs.empty());
  const auto& first = costs.front();
  ASSERT_EQ(runHattr(dir, "study export --db " + db + " --out " + (dir / "export").string()).exit_code, 0);
  std::string trial_file;
  std::istringstream trials(test::readText(dir / "export" / "trials.csv"));
  const auto field = [](const std::string& line, std::size_t n) {  // the n-th comma-separated field, from 0
    std::istringstream split(line);
    std::string f;
    for (std::size_t i = 0; i <= n; ++i) std::getline(split, f, ',');
    return f;
  };
  for (std::string line; std::getline(trials, line);) {
    if (line.starts_with(fmt::format("{},", first["trial_id"].get<std::int64_t>()))) trial_file = field(line, 14);
  }
  ASSERT_FALSE(trial_file.empty());
  const RunResult scored = runHattr(dir, "dtw --score --json " + (dir / "export" / "experts" / "na.csv").string() + " " +
                                             (dir / "export" / trial_file).string());
  ASSERT_EQ(scored.exit_code, 0) << scored.err;
  const auto score = nlohmann::json::parse(scored.out);
  EXPECT_NEAR(score["shape"].get<double>(), first["trajectory"].get<double>(), 1e-12);
  EXPECT_NEAR(score["force"].get<double>(), first["force"].get<double>(), 1e-12);
  EXPECT_NEAR(score["height"].get<double>(), first["z"].get<double>(), 1e-12);
}

// R's warpbreaks, as write.csv(warpbreaks, row.names = FALSE) writes it (quoted fields).
constexpr const char* kWarpbreaks = "\"breaks\",\"wool\",\"tension\"\n26,\"A\",\"L\"\n30,\"A\",\"L\"\n54,\"A\",\"L\"\n25,\"A\",\"L\"\n70,\"A\",\"L\"\n52,\"A\",\"L\"\n51,\"A\",\"L\"\n26,\"A\",\"L\"\n67,\"A\",\"L\"\n18,\"A\",\"M\"\n21,\"A\",\"M\"\n29,\"A\",\"M\"\n17,\"A\",\"M\"\n12,\"A\",\"M\"\n18,\"A\",\"M\"\n35,\"A\",\"M\"\n30,\"A\",\"M\"\n36,\"A\",\"M\"\n36,\"A\",\"H\"\n21,\"A\",\"H\"\n24,\"A\",\"H\"\n18,\"A\",\"H\"\n10,\"A\",\"H\"\n43,\"A\",\"H\"\n28,\"A\",\"H\"\n15,\"A\",\"H\"\n26,\"A\",\"H\"\n27,\"B\",\"L\"\n14,\"B\",\"L\"\n29,\"B\",\"L\"\n19,\"B\",\"L\"\n29,\"B\",\"L\"\n31,\"B\",\"L\"\n41,\"B\",\"L\"\n20,\"B\",\"L\"\n44,\"B\",\"L\"\n42,\"B\",\"M\"\n26,\"B\",\"M\"\n19,\"B\",\"M\"\n16,\"B\",\"M\"\n39,\"B\",\"M\"\n28,\"B\",\"M\"\n21,\"B\",\"M\"\n39,\"B\",\"M\"\n29,\"B\",\"M\"\n20,\"B\",\"H\"\n21,\"B\",\"H\"\n24,\"B\",\"H\"\n17,\"B\",\"H\"\n13,\"B\",\"H\"\n15,\"B\",\"H\"\n15,\"B\",\"H\"\n16,\"B\",\"H\"\n28,\"B\",\"H\"\n";

TEST(Cli, AnovaMatchesRsAovAndTukeyOnAQuotedCsv) {
  test::TempDir dir;
  test::writeText(dir / "wb.csv", kWarpbreaks);
  const RunResult r = runHattr(dir, "anova --json --response breaks --factor tension --factor wool --tukey tension " +
                                        (dir / "wb.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto json = nlohmann::json::parse(r.out);
  // R 4.2.2, options(digits = 15): s <- summary(aov(breaks ~ tension * wool, data = warpbreaks))[[1]];
  // s[["F value"]]; s[["Pr(>F)"]]; TukeyHSD(aov(breaks ~ tension * wool, data = warpbreaks), "tension")
  const auto rel = [](double got, double want) { return std::abs(got - want) / std::abs(want); };
  ASSERT_EQ(json["rows"].size(), 4u);
  EXPECT_EQ(json["rows"][2]["source"], "tension:wool");
  EXPECT_LT(rel(json["rows"][0]["f"].get<double>(), 8.49804664835802), 1e-8);
  EXPECT_LT(rel(json["rows"][0]["p"].get<double>(), 0.000692620936713444), 1e-8);
  EXPECT_LT(rel(json["rows"][2]["p"].get<double>(), 0.021044190727862934), 1e-8);
  EXPECT_EQ(json["rows"][3]["df"].get<int>(), 48);
  EXPECT_LT(rel(json["tukey"]["comparisons"][1]["p_adj"].get<double>(), 0.000559539221793859), 1e-6);
  const RunResult bad = runHattr(dir, "anova --response breaks --factor tension --factor colour " + (dir / "wb.csv").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.err, HasSubstr("no column \"colour\": expected one of breaks, wool, tension"));
}

TEST(Cli, DtwJsonHasCostPerChannelAndThePathWhenAsked) {
  test::TempDir dir;
  test::writeText(dir / "a.csv", handScript());
  test::writeText(dir / "b.csv", handScript(3.0));
  const RunResult r = runHattr(dir, "dtw --json --path --channels x,y,fz --band 0.2 " + (dir / "a.csv").string() + " " +
                                        (dir / "b.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["cost_fn"], "abs");
  EXPECT_EQ(json["band"].get<double>(), 0.2);
  EXPECT_DOUBLE_EQ(json["cost"]["x"].get<double>(), 0.0);  // same x: identical after preprocessing
  EXPECT_GT(json["cost"]["y"].get<double>(), 0.0);           // y drifts in B
  EXPECT_EQ(json["path"]["y"].front(), nlohmann::json::array({0, 0}));
  EXPECT_EQ(json["path"]["y"].back(), nlohmann::json::array({100, 100}));
  EXPECT_EQ(runHattr(dir, "dtw --channels q " + (dir / "a.csv").string() + " " + (dir / "b.csv").string()).exit_code, 2);
}

}  // namespace
}  // namespace hattr
