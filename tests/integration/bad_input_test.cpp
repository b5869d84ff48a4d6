// The bad-input corpus: files a new user or an attacker could hand hattr — study, world,
// profile, hand-script and database files, and arguments — each run through the real binary.
// Every case must exit 2 with a short message that names the file, and leave nothing behind.

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/run_command.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// ---- Good inputs, to be broken ---------------------------------------------------------

/// A short pen stroke: 40 samples at 100 Hz, pressing 1.5 N.
std::string goodProfile() {
  std::string text = "# subject: S1\n# skill: dash\nt_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n";
  for (int i = 0; i < 40; ++i) text += fmt::format("{},{},0.01,0,0,0,-1.5,1\n", i * 0.01, 0.001 * i);
  return text;
}

/// A valid study of `expert.csv` with `replace` applied to its text (a key's value swapped).
std::string study(const std::string& from = "", const std::string& to = "") {
  std::string text =
      R"({"name": "corpus", "skill": "dash", "experts": {"dash": "expert.csv"}, "modes": ["basic", "pcontrol"],)"
      R"( "protocol": {"training_trials": 1, "recall_trials": 1, "rest_s": 0, "tail_s": 0.05},)"
      R"( "world": {"relief": {"kind": "flat"}}, "subjects": {"count": 2, "participant": "script"}})";
  if (!from.empty()) {
    const auto at = text.find(from);
    if (at == std::string::npos) throw std::logic_error("test study: no \"" + from + "\" to replace");
    text.replace(at, from.size(), to);
  }
  return text;
}

std::string nested(int depth) { return std::string(static_cast<std::size_t>(depth), '[') + std::string(static_cast<std::size_t>(depth), ']'); }

/// A database with its trials run (made once per test program, copied for each case).
const fs::path& goodDatabase() {
  static test::TempDir dir;
  static const fs::path db = [] {
    test::writeText(dir / "expert.csv", goodProfile());
    test::writeText(dir / "study.json", study());
    const auto init = test::runCommand(dir, test::builtFile("HATTR_CLI"), "study init " + (dir / "study.json").string() + " --db " +
                                                                (dir / "good.sqlite").string());
    const auto run = test::runCommand(dir, test::builtFile("HATTR_CLI"), "study run --quiet --db " + (dir / "good.sqlite").string());
    if (init.exit_code != 0 || run.exit_code != 0) throw std::runtime_error("corpus database: " + init.err + run.err);
    return dir / "good.sqlite";
  }();
  return db;
}

/// Copies the good database into `dir` as `name` and runs `sql` on the copy.
fs::path damagedDatabase(const fs::path& dir, const std::string& name, const std::string& sql) {
  const fs::path file = dir / name;
  fs::copy_file(goodDatabase(), file);
  sqlite3* db = nullptr;
  if (sqlite3_open(file.c_str(), &db) != SQLITE_OK || sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK) {
    const std::string message = db ? sqlite3_errmsg(db) : "open";
    sqlite3_close(db);
    throw std::runtime_error("damaging the database: " + message);
  }
  sqlite3_exec(db, "PRAGMA wal_checkpoint(TRUNCATE)", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  return file;
}

/// Overwrites `count` bytes of `file` at `offset` with 0xA5.
void scribble(const fs::path& file, std::size_t offset, std::size_t count) {
  std::string bytes = test::readText(file);
  for (std::size_t i = offset; i < offset + count && i < bytes.size(); ++i) bytes[i] = static_cast<char>(0xA5);
  test::writeText(file, bytes);
}

// ---- The corpus ------------------------------------------------------------------------

struct BadInput {
  std::string name;
  /// Writes the bad input into the case's folder; returns the command's arguments.
  std::function<std::string(const fs::path& dir)> prepare;
  std::string expect;  ///< in the message
  std::string names;   ///< the file (in the case's folder) the message must name; "" for arguments
};

std::string q(const fs::path& p) { return p.string(); }

/// A profile file read by `profile info`.
BadInput profileCase(std::string name, std::string text, std::string expect) {
  return {std::move(name),
          [text](const fs::path& dir) {
            test::writeText(dir / "p.csv", text);
            return "profile info " + q(dir / "p.csv");
          },
          std::move(expect), "p.csv"};
}

/// A hand script read by `record`: no output may appear.
BadInput handCase(std::string name, std::string text, std::string expect) {
  return {std::move(name),
          [text](const fs::path& dir) {
            test::writeText(dir / "hand.csv", text);
            return "record --clock sim --hand " + q(dir / "hand.csv") + " -o " + q(dir / "out.csv");
          },
          std::move(expect), "hand.csv"};
}

/// A world file read by `world check` and by `record --world`.
BadInput worldCase(std::string name, std::string text, std::string expect) {
  return {std::move(name),
          [text](const fs::path& dir) {
            test::writeText(dir / "world.json", text);
            return "world check " + q(dir / "world.json");
          },
          std::move(expect), "world.json"};
}

/// A study file read by `study init`: no database may appear.
BadInput studyCase(std::string name, std::string text, std::string expect) {
  return {std::move(name),
          [text](const fs::path& dir) {
            test::writeText(dir / "expert.csv", goodProfile());
            test::writeText(dir / "study.json", text);
            return "study init " + q(dir / "study.json") + " --db " + q(dir / "s.sqlite");
          },
          std::move(expect), "study.json"};
}

/// A damaged copy of a good database, read by `command` (status, export...).
BadInput databaseCase(std::string name, std::string sql, std::string command, std::string expect) {
  return {std::move(name),
          [sql, command](const fs::path& dir) {
            const fs::path db = damagedDatabase(dir, "d.sqlite", sql);
            return fmt::format(fmt::runtime(command), q(db), q(dir / "export"));
          },
          std::move(expect), "d.sqlite"};
}

std::vector<BadInput> corpus() {
  const std::string header = "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n";
  std::vector<BadInput> c;
  // Profiles.
  c.push_back(profileCase("profile_empty", "", "empty file"));
  c.push_back(profileCase("profile_only_metadata", "# subject: x\n", "expected a column row"));
  c.push_back(profileCase("profile_no_rows", header, "no data rows"));
  c.push_back(profileCase("profile_field_count", header + "0,0,0,0,0,0,0,1\n0.1,0,0,0,0,1\n", ":3: expected 8 fields, got 6"));
  c.push_back(profileCase("profile_not_a_number", header + "0,0,0,0,0,0,abc,1\n", "expected a number, got \"abc\""));
  c.push_back(profileCase("profile_nan", header + "0,0,0,0,0,0,nan,1\n", "expected a finite number"));
  c.push_back(profileCase("profile_inf", header + "0,inf,0,0,0,0,0,1\n", "expected a finite number"));
  c.push_back(profileCase("profile_time_backwards", header + "0.1,0,0,0,0,0,0,1\n0.05,0,0,0,0,0,0,1\n", ":3:"));
  c.push_back(profileCase("profile_unknown_unit", "t_s,x_in,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,0,1\n",
                          "unknown unit for x"));
  c.push_back(profileCase("profile_missing_column", "t_s,x_m,y_m,z_m,fx_N,fy_N,pen_down_bool\n0,0,0,0,0,0,1\n",
                          "missing required column"));
  c.push_back(profileCase("profile_duplicate_column", "t_s,x_m,x_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,0,1\n", "x"));
  c.push_back(profileCase("profile_flag_two", header + "0,0,0,0,0,0,0,2\n", "expected 0 or 1"));
  c.push_back(profileCase("profile_absurd_position", header + "0,1e154,0,0,0,0,0,1\n", "expected at most 1 m"));
  c.push_back(profileCase("profile_absurd_force", header + "0,0,0,0,0,0,-5000,1\n", "expected at most 1000 N"));
  c.push_back(profileCase("profile_control_character", "# subject: a\x01" "b\n" + header + "0,0,0,0,0,0,0,1\n",
                          "control character"));
  c.push_back(profileCase("profile_newer_format", "# format: hattr-profile/9\n" + header + "0,0,0,0,0,0,0,1\n",
                          "hattr-profile/9"));
  c.push_back(profileCase("profile_binary_garbage", std::string("\x7f" "ELF\x02\x01\x01\0\0\0", 10) + "\x90\x90\n",
                          "p.csv"));
  c.push_back(profileCase("profile_half_velocity", "t_s,x_m,y_m,z_m,vx_m_per_s,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,0,0,1\n",
                          "v"));
  c.push_back({"profile_is_a_folder",
               [](const fs::path& dir) {
                 fs::create_directory(dir / "p.csv");
                 return "profile info " + q(dir / "p.csv");
               },
               "expected a file", "p.csv"});
  c.push_back({"profile_missing",
               [](const fs::path& dir) { return "profile info " + q(dir / "p.csv"); }, "cannot open", "p.csv"});
  // Hand scripts: the trial never starts, no output appears.
  c.push_back(handCase("hand_empty", "", "empty file"));
  c.push_back(handCase("hand_absurd_position", header + "0,0,0,0,0,0,-1,1\n0.01,3,0,0,0,0,-1,1\n", "expected at most 1 m"));
  c.push_back(handCase("hand_nan_force", header + "0,0,0,0,0,0,nan,1\n", "expected a finite number"));
  c.push_back(handCase("hand_absurd_force", header + "0,0,0,0,0,0,-1e300,1\n", "expected at most 1000 N"));
  // Worlds.
  c.push_back(worldCase("world_not_json", "{paper: soft}", "not valid JSON"));
  c.push_back(worldCase("world_array", "[1, 2]", "expected a JSON object, got array"));
  c.push_back(worldCase("world_unknown_key", R"({"papr": {}})", "unknown key \"papr\""));
  c.push_back(worldCase("world_deep", R"({"paper": )" + nested(100000) + "}", "nested deeper than 64 levels"));
  c.push_back(worldCase("world_number_overflow", R"({"paper": {"stiffness_N_per_m": 1e400}})", "not valid JSON"));
  c.push_back(worldCase("world_wrong_type", R"({"paper": {"stiffness_N_per_m": "hard"}})", "stiffness"));
  c.push_back(worldCase("world_negative_stiffness", R"({"paper": {"stiffness_N_per_m": -1}})", "stiffness"));
  c.push_back(worldCase("world_relief_missing_file", R"({"relief": {"kind": "pgm", "file": "nowhere.pgm"}})", "nowhere"));
  c.push_back(worldCase("world_relief_unknown_kind", R"({"relief": {"kind": "moon"}})", "moon"));
  c.push_back(worldCase("world_huge_value", R"({"paper": {"stiffness_N_per_m": ")" + std::string(50000, 'x') + "\"}}",
                        "characters)"));
  c.push_back(worldCase("world_empty", "", "not valid JSON"));
  // Studies: no database appears.
  c.push_back(studyCase("study_not_json", "{", "not valid JSON"));
  c.push_back(studyCase("study_unknown_key", study("\"name\"", "\"colour\": 1, \"name\""), "unknown key \"colour\""));
  c.push_back(studyCase("study_zero_trials", study("\"training_trials\": 1, \"recall_trials\": 1",
                                                   "\"training_trials\": 0, \"recall_trials\": 0"),
                        "zero trials"));
  c.push_back(studyCase("study_traversal_id", study(R"("subjects": {"count": 2, "participant": "script"})",
                                                    R"("subjects": [{"id": "../../x", "participant": "script"}])"),
                        "subject id \"../../x\""));
  c.push_back(studyCase("study_traversal_skill", study(R"("skill": "dash", "experts": {"dash": "expert.csv"})",
                                                       R"("skill": "../d", "experts": {"../d": "expert.csv"})"),
                        "skill \"../d\""));
  c.push_back(studyCase("study_duplicate_id", study(R"("subjects": {"count": 2, "participant": "script"})",
                                                    R"("subjects": [{"id": "A"}, {"id": "A"}])"),
                        "used twice"));
  c.push_back(studyCase("study_missing_expert", study("expert.csv", "nobody.csv"), "not found"));
  c.push_back(studyCase("study_wrong_type", study("\"count\": 2", "\"count\": 2, \"prefix\": 5"), "study.json"));
  c.push_back(studyCase("study_number_overflow", study("\"rest_s\": 0", "\"rest_s\": 1e400"), "not valid JSON"));
  c.push_back(studyCase("study_deep", study("\"name\": \"corpus\"", "\"name\": " + nested(5000)),
                        "nested deeper than 64 levels"));
  c.push_back(studyCase("study_unknown_mode", study("\"pcontrol\"", "\"gamma\""), "got \"gamma\""));
  c.push_back(studyCase("study_mentored_without_connect", study("\"pcontrol\"]", R"("mentor-position"], "mentor": {"expert": "live"})"),
                        "mentor.connect"));
  // A strategy's parameter in the study file: checked at init as `--param` is.
  c.push_back(studyCase("study_strategy_parameter_out_of_range",
                        study("\"name\"", R"("strategy_parameters": {"fading": {"end_gain": 2}}, "name")"),
                        "strategy_parameters: FADING end_gain: expected 0 to 1, got 2"));
  c.push_back(studyCase("study_strategy_parameter_bad_choice",
                        study("\"name\"", R"("strategy_parameters": {"assist-as-needed": {"base": "noise"}}, "name")"),
                        "ASSIST-AS-NEEDED base: expected one of pcontrol, alpha, got \"noise\""));
  c.push_back(studyCase("study_strategy_parameters_twice",
                        study("\"name\"", R"("strategy_parameters": {"Fading": {}, "fading": {}}, "name")"),
                        "fading is given twice"));
  c.push_back(studyCase("study_strategy_parameter_unknown_strategy",
                        study("\"name\"", R"("strategy_parameters": {"fadeing": {}}, "name")"),
                        "strategy_parameters: mode: expected one of"));
  c.push_back(studyCase("study_negative_rate", study("\"name\"", "\"rate_hz\": -5, \"name\""), "rate_hz"));
  c.push_back(studyCase("study_expert_absurd", study(), "expected at most 1 m"));
  c.back().prepare = [](const fs::path& dir) {  // the expert reference itself is absurd
    test::writeText(dir / "expert.csv", "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,-1,1\n0.01,40,0,0,0,0,-1,1\n");
    test::writeText(dir / "study.json", study());
    return "study init " + q(dir / "study.json") + " --db " + q(dir / "s.sqlite");
  };
  c.back().names = "expert.csv";
  // Issue 38: an expert pressing harder than the study's pen renders is refused at init.
  c.push_back(studyCase("study_expert_past_the_device", study(), "more than the device's continuous force of 1.75 N"));
  c.back().prepare = [](const fs::path& dir) {
    test::writeText(dir / "expert.csv",
                    "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,-1,1\n0.01,0.001,0,0,0,0,-3.3,1\n");
    test::writeText(dir / "study.json", study());
    return "study init " + q(dir / "study.json") + " --db " + q(dir / "s.sqlite");
  };
  c.back().names = "expert.csv";
  c.push_back(studyCase("study_is_array", "[]", "expected a JSON object"));
  // Found by the fuzzer: a subjects object without its count was a study of nobody.
  c.push_back(studyCase("study_subjects_without_count", study("\"count\": 2", "\"coun%\": 2"),
                        "subjects: unknown key \"coun%\""));
  // Databases.
  c.push_back({"db_text_file",
               [](const fs::path& dir) {
                 test::writeText(dir / "d.sqlite", "hello, I am not a database\n");
                 return "study status --db " + q(dir / "d.sqlite");
               },
               "not a hattr study database", "d.sqlite"});
  c.push_back({"db_empty_file",
               [](const fs::path& dir) {
                 test::writeText(dir / "d.sqlite", "");
                 return "study status --db " + q(dir / "d.sqlite");
               },
               "not a hattr study database", "d.sqlite"});
  c.push_back({"db_other_application",
               [](const fs::path& dir) {
                 sqlite3* db = nullptr;
                 sqlite3_open((dir / "d.sqlite").c_str(), &db);
                 sqlite3_exec(db, "CREATE TABLE t (x); PRAGMA application_id = 42;", nullptr, nullptr, nullptr);
                 sqlite3_close(db);
                 return "study status --db " + q(dir / "d.sqlite");
               },
               "application id 0x2a", "d.sqlite"});
  c.push_back(databaseCase("db_newer_schema", "PRAGMA user_version = 99", "study status --db {}", "newer than"));
  c.push_back(databaseCase("db_dropped_trials", "DROP TABLE samples; DROP TABLE disturbed_attempts; DROP TABLE trials;",
                           "study status --db {}", "damaged"));
  c.push_back(databaseCase("db_broken_subject_json", "UPDATE subjects SET spec = '{\"participant\": ' WHERE position = 0",
                           "study status --db {}", "subject S01 is damaged"));
  c.push_back(databaseCase("db_broken_definition", "UPDATE study SET definition = '{\"name\": 3'", "study status --db {}",
                           "not valid JSON"));
  c.push_back(databaseCase("db_short_sample_blob", "UPDATE samples SET data = substr(data, 1, 100) WHERE trial = 2",
                           "study export --db {} --out {}", "trial 2 (subject S01, sequence 1) is damaged: samples"));
  c.push_back(databaseCase("db_broken_trial_metadata", "UPDATE trials SET metadata = '{\"subject\": }' WHERE id = 3",
                           "study export --db {} --out {}", "trial 3 (subject S01, sequence 2) is damaged: metadata"));
  c.push_back(databaseCase("db_absurd_sample_count", "UPDATE samples SET sample_count = 9000000000000000000 WHERE trial = 1",
                           "study export --db {} --out {}", "trial 1 (subject S01, sequence 0) is damaged"));
  c.push_back({"db_corrupt_pages",
               [](const fs::path& dir) {
                 const fs::path db = damagedDatabase(dir, "d.sqlite", "PRAGMA journal_mode = DELETE");
                 scribble(db, 4096, 8192);  // pages 2 and 3: the schema's tables
                 return "study export --db " + q(db) + " --out " + q(dir / "export");
               },
               "d.sqlite", "d.sqlite"});
  c.push_back({"db_truncated",
               [](const fs::path& dir) {
                 const fs::path db = damagedDatabase(dir, "d.sqlite", "PRAGMA journal_mode = DELETE");
                 fs::resize_file(db, 3000);
                 return "study status --db " + q(db);
               },
               "d.sqlite", "d.sqlite"});
  c.push_back({"db_missing",
               [](const fs::path& dir) { return "study status --db " + q(dir / "d.sqlite"); }, "no such study database",
               "d.sqlite"});
  c.push_back({"db_import_damaged_trials_table",
               [](const fs::path& dir) {
                 fs::create_directories(dir / "export");
                 test::writeText(dir / "export" / "expert.csv", goodProfile());
                 test::writeText(dir / "export" / "study.json", study());
                 test::writeText(dir / "export" / "trials.csv", "id,subject\n");
                 return "study import " + q(dir / "export") + " --db " + q(dir / "d.sqlite");
               },
               "expected the header", "export/trials.csv"});
  // Arguments.
  c.push_back({"args_unknown_option", [](const fs::path&) { return std::string("profile info --colour x"); },
               "colour", ""});
  c.push_back({"args_out_of_range", [](const fs::path& dir) { return "world check " + q(dir / "w.json") + " --rate 0"; },
               "rate", ""});
  // Issue 36: a strategy's parameter outside its range, named with its range and unit.
  const auto trainWith = [](const std::string& tail) {
    return [tail](const fs::path& dir) {
      const std::string script = "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,-1,1\n0.01,0.001,0,0,0,0,-1,1\n";
      test::writeText(dir / "hand.csv", script);
      return "train --hand " + q(dir / "hand.csv") + " --reference " + q(dir / "hand.csv") + " -o " + q(dir / "t.csv") +
             " " + tail;
    };
  };
  c.push_back({"args_strategy_parameter_out_of_range", trainWith("--mode channel --param half_width_mm=50"),
               "CHANNEL half_width_mm: expected 0 to 20 mm, got 50", ""});
  c.push_back({"args_strategy_parameter_unknown", trainWith("--mode noise --param width=1"),
               "NOISE: no parameter \"width\": expected one of rms_N, cutoff_hz", ""});
  c.push_back({"args_strategy_unknown", trainWith("--mode chanel"), "expected one of basic, pcontrol, alpha", ""});
  // Issue 37: mixed models of a table, each refusal naming the file and what it found.
  const auto lmmWith = [](const std::string& table, const std::string& tail) {
    return [table, tail](const fs::path& dir) {
      test::writeText(dir / "t.csv", table);
      return "lmm " + q(dir / "t.csv") + " " + tail;
    };
  };
  const std::string table = "subject,mode,cost\nA,x,1\nA,y,2\nB,x,1.5\nB,y,2.5\nC,x,0.5\nC,y,3\n";
  c.push_back({"lmm_unknown_column", lmmWith(table, "--formula 'cost ~ mode + (1 | sbject)'"),
               "the formula names column 'sbject', which is not in the table; columns: subject, mode, cost", "t.csv"});
  c.push_back({"lmm_formula_unparsed", lmmWith(table, "--formula 'cost ~ mode + (1 | subject'"), "expected ')'", ""});
  c.push_back({"lmm_no_random_term", lmmWith(table, "--formula 'cost ~ mode'"), "no random-effects term", ""});
  c.push_back({"lmm_missing_value", lmmWith("subject,mode,cost\nA,x,1\nA,y,NA\nB,x,2\nB,y,3\n", "--formula 'cost ~ mode + (1 | subject)'"),
               "row 2 of column 'cost' is missing", "t.csv"});
  c.push_back({"lmm_infinite_value", lmmWith("subject,mode,cost\nA,x,1\nA,y,inf\nB,x,2\nB,y,3\n", "--formula 'cost ~ mode + (1 | subject)'"),
               "row 2 of column 'cost' is 'inf'; expected a finite number", "t.csv"});
  c.push_back({"lmm_one_level_factor", lmmWith("subject,mode,cost\nA,x,1\nA,x,2\nB,x,2\nB,x,3\n", "--formula 'cost ~ mode + (1 | subject)'"),
               "factor 'mode' has one level ('x')", "t.csv"});
  c.push_back({"lmm_bad_reference", lmmWith(table, "--formula 'cost ~ mode + (1 | subject)' --reference mode"),
               "expected COLUMN=LEVEL", ""});
  c.push_back({"lmm_compare_models_of_one_size", lmmWith(table, "--formula 'cost ~ mode + (1 | subject)' --formula 'cost ~ mode + (1 | subject)'"),
               "needs nested models of different sizes", ""});
  return c;
}

class BadInputCorpus : public ::testing::TestWithParam<BadInput> {};

std::set<std::string> filesUnder(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir)) names.insert(fs::relative(e.path(), dir).string());
  return names;
}

TEST_P(BadInputCorpus, ExitsTwoNamingTheFileAndLeavesNothingBehind) {
  HATTR_STARTS_NO_THREAD();
  const BadInput& c = GetParam();
  test::TempDir dir;
  const std::string args = c.prepare(dir.path());
  std::set<std::string> before = filesUnder(dir.path());
  before.insert({"run.out", "run.err"});
  const test::RunResult r = test::runCommand(dir, test::builtFile("HATTR_CLI"), args);
  EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
  EXPECT_THAT(r.err, HasSubstr(c.expect)) << args;
  if (!c.names.empty()) {
    EXPECT_THAT(r.err, HasSubstr((dir / c.names).string())) << args;
  }
  EXPECT_LT(r.err.size(), 2000u) << "an unbounded message";
  EXPECT_EQ(r.err.find("[json.exception"), std::string::npos) << "a library's text: " << r.err;
  EXPECT_EQ(filesUnder(dir.path()), before) << "left behind by: " << args;
}

INSTANTIATE_TEST_SUITE_P(Cases, BadInputCorpus, ::testing::ValuesIn(corpus()),
                         [](const ::testing::TestParamInfo<BadInput>& param) { return param.param.name; });

TEST(BadInputCorpus, HoldsAtLeastSixtyCasesOfEveryKind) {
  const auto all = corpus();
  EXPECT_GE(all.size(), 60u);
  for (const std::string kind : {"profile_", "hand_", "world_", "study_", "db_", "args_"}) {
    EXPECT_TRUE(std::any_of(all.begin(), all.end(), [&](const BadInput& c) { return c.name.starts_with(kind); })) << kind;
  }
}

// A spreadsheet's UTF-8 byte-order mark is not a channel name: such a file reads.
TEST(BadInputCorpus, AProfileWithAByteOrderMarkReads) {
  test::TempDir dir;
  test::writeText(dir / "p.csv", "\xEF\xBB\xBF" + goodProfile());
  const test::RunResult r = test::runCommand(dir, test::builtFile("HATTR_CLI"), "profile info " + q(dir / "p.csv"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// ---- Outputs: checked before any work, replaced only with --force -----------------------

// A second report into the same folder is refused before anything is written (the first kept
// as it was), names --force, and --force replaces it.
TEST(Outputs, AReportIsNeverOverwrittenWithoutForceAndEveryOutputIsCheckedFirst) {
  test::TempDir dir;
  fs::copy_file(goodDatabase(), dir / "s.sqlite");
  const std::string report = "study report --db " + q(dir / "s.sqlite") + " --out " + q(dir / "report");
  ASSERT_EQ(test::runCommand(dir, test::builtFile("HATTR_CLI"), report).exit_code, 0);
  test::writeText(dir / "report" / "report.md", "my notes");
  const test::RunResult again = test::runCommand(dir, test::builtFile("HATTR_CLI"), report);
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_THAT(again.err, HasSubstr("already exists; add --force to replace it (nothing was written)"));
  EXPECT_EQ(test::readText(dir / "report" / "report.md"), "my notes");
  EXPECT_EQ(test::runCommand(dir, test::builtFile("HATTR_CLI"), report + " --force").exit_code, 0);
  EXPECT_NE(test::readText(dir / "report" / "report.md"), "my notes");
  // An --out that is a file: refused before the analysis is stored or anything written.
  test::writeText(dir / "taken", "a file");
  const test::RunResult file = test::runCommand(dir, test::builtFile("HATTR_CLI"), "study analyze --db " + q(dir / "s.sqlite") + " --out " + q(dir / "taken"));
  EXPECT_EQ(file.exit_code, 2);
  EXPECT_THAT(file.err, HasSubstr(q(dir / "taken") + ": expected a folder"));
}

// A command with two outputs writes neither when the second is taken; a trial is not run
// when its recording could not be written.
TEST(Outputs, TwoOutputsAreCheckedBeforeEitherIsWrittenAndATrialBeforeItRuns) {
  test::TempDir dir;
  test::writeText(dir / "script.csv", "mine");
  const test::RunResult sim = test::runCommand(dir, test::builtFile("HATTR_CLI"), "sim expert -o " + q(dir / "expert.csv") + " --script-out " + q(dir / "script.csv"));
  EXPECT_EQ(sim.exit_code, 2);
  EXPECT_THAT(sim.err, HasSubstr(q(dir / "script.csv") + ": already exists; add --force"));
  EXPECT_FALSE(fs::exists(dir / "expert.csv"));
  EXPECT_EQ(test::readText(dir / "script.csv"), "mine");

  test::writeText(dir / "hand.csv", goodProfile());
  test::writeText(dir / "out.csv", "an earlier recording");
  const test::RunResult record = test::runCommand(dir, test::builtFile("HATTR_CLI"), "record --clock sim --hand " + q(dir / "hand.csv") + " -o " + q(dir / "out.csv"));
  EXPECT_EQ(record.exit_code, 2);
  EXPECT_THAT(record.err, HasSubstr("add --force"));
  EXPECT_EQ(test::readText(dir / "out.csv"), "an earlier recording");
  const test::RunResult nowhere = test::runCommand(dir, test::builtFile("HATTR_CLI"), "record --clock sim --hand " + q(dir / "hand.csv") + " -o " + q(dir / "no" / "out.csv"));
  EXPECT_EQ(nowhere.exit_code, 2);
  EXPECT_THAT(nowhere.err, HasSubstr(q(dir / "no") + ": no such folder"));
}

// ---- Study databases in use or shared ----------------------------------------------------

// While a runner holds the study, its running trial is running, not interrupted.
TEST(StudyStatus, ARunningTrialOfALiveRunnerIsNotCountedInterrupted) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  fs::copy_file(goodDatabase(), dir / "s.sqlite");
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "s.sqlite").c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, "UPDATE trials SET status = 'running' WHERE subject = 'S01' AND sequence = 3", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(raw);
  const std::string status = "study status --json --db " + q(dir / "s.sqlite");
  {
    // A runner's lock, as `study run` holds it.
    const int fd = ::open((dir / "s.sqlite").c_str(), O_RDONLY | O_CLOEXEC);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
    const test::RunResult during = test::runCommand(dir, test::builtFile("HATTR_CLI"), status);
    ::close(fd);
    ASSERT_EQ(during.exit_code, 0) << during.err;
    EXPECT_THAT(during.out, HasSubstr("\"trials_running\": 1"));
    EXPECT_THAT(during.out, HasSubstr("\"trials_interrupted\": 0"));
    EXPECT_THAT(during.out, HasSubstr("\"runner_active\": true"));
  }
  // Nobody holds it: that trial's runner died.
  const test::RunResult after = test::runCommand(dir, test::builtFile("HATTR_CLI"), status);
  EXPECT_THAT(after.out, HasSubstr("\"trials_running\": 0"));
  EXPECT_THAT(after.out, HasSubstr("\"trials_interrupted\": 1"));
}

// A study in a folder the reader cannot write (a shared, read-only copy) reads. As root every
// folder is writable, so the test runs the reader as the user nobody when it can.
TEST(StudyStatus, AStudyInAReadOnlyFolderReads) {
  test::TempDir dir;
  fs::create_directory(dir / "shared");
  fs::copy_file(goodDatabase(), dir / "shared" / "s.sqlite");
  fs::permissions(dir / "shared" / "s.sqlite", fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  fs::permissions(dir / "shared", fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                                      fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  std::string prefix;
  if (::geteuid() == 0) {
    if (std::system("command -v runuser >/dev/null 2>&1 && id nobody >/dev/null 2>&1") != 0) {
      GTEST_SKIP() << "running as root without runuser or the user nobody: every folder is writable to root";
    }
    fs::permissions(dir.path(), fs::perms::others_exec | fs::perms::others_read, fs::perm_options::add);
    prefix = "runuser -u nobody -- ";
  }
  // A copy of the binary nobody can run (the build tree may sit in a folder only root enters).
  fs::copy_file(test::builtFile("HATTR_CLI"), dir / "hattr");
  fs::permissions(dir / "hattr", fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                     fs::perms::others_read | fs::perms::others_exec);
  const test::RunResult r = test::runCommand(dir, prefix + q(dir / "hattr"), "study status --json --db " + q(dir / "shared" / "s.sqlite"));
  fs::permissions(dir / "shared", fs::perms::owner_all, fs::perm_options::add);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("\"trials_completed\": 8"));
  EXPECT_EQ(filesUnder(dir / "shared"), std::set<std::string>{"s.sqlite"});
}

}  // namespace
}  // namespace hattr
