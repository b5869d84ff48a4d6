// hattr library init|import|add|list|show|remove|export|verify|identify|evaluate: the profile
// library (docs/library.md), each an ops:: call.

#include <cstdlib>
#include <iostream>
#include <memory>
#include <set>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/io/table_csv.hpp"
#include "hattr/library/profile_template.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/ops/library.hpp"
#include "hattr/report/library_report.hpp"

namespace hattr::cli {
namespace {

namespace fs = std::filesystem;

/// The library every subcommand works on: --library, else $HATTR_LIBRARY, else library.sqlite here.
struct LibraryChoice {
  std::string location;
  [[nodiscard]] std::string resolved() const {
    if (!location.empty()) return location;
    const char* env = std::getenv("HATTR_LIBRARY");
    return env != nullptr && *env != '\0' ? env : "library.sqlite";
  }
};

/// Adds to the library, which is made first if it is a file that does not exist yet (said on
/// stderr) and removed again if the adding fails: a failed first import leaves nothing behind.
template <class Add>
ops::LibraryChange addToLibrary(const LibraryChoice& choice, Add add) {
  const std::string location = choice.resolved();
  const bool made = !library::isDatabaseAddress(location) && !fs::exists(location);
  if (made) ops::libraryInit(location);
  try {
    auto change = add(location);
    if (made) std::cerr << "made a new profile library at " << location << '\n';
    return change;
  } catch (...) {
    if (made) {
      std::error_code ignored;
      for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(location + suffix, ignored);
    }
    throw;
  }
}

void printChange(const ops::LibraryChange& c, bool json, std::string_view verb) {
  if (json) {
    printJson(c.toJson());
    return;
  }
  std::cout << fmt::format("{} {} {} {}\n", c.library, verb, c.keys.size(), c.keys.size() == 1 ? "entry" : "entries");
}

/// The feature and matching options shared by verify, identify and evaluate.
struct MatchFlags {
  std::string features = "shape+force";
  std::size_t length = library::FeatureOptions{}.length;
  double band = library::FeatureOptions{}.band_fraction;
  double timing_weight = library::FeatureOptions{}.timing_weight;
  std::string rule = "mean";
  std::string normalization = "paper";
  void add(CLI::App& cmd, bool with_features) {
    if (with_features) {
      cmd.add_option("--features", features, "Feature set: shape, force, angles, velocity, timing joined with '+', or all")
          ->capture_default_str();
    }
    cmd.add_option("--length", length, "Steps every profile is resampled at")->capture_default_str();
    cmd.add_option("--band", band, "DTW band (and LB_Keogh radius) as a fraction of the length")->capture_default_str();
    cmd.add_option("--timing-weight", timing_weight, "Weight of the timing feature's |ln(T_a / T_b)|")
        ->capture_default_str();
    cmd.add_option("--rule", rule, "How distances to a person's references make a score: mean or min")
        ->capture_default_str();
    cmd.add_option("--normalization", normalization, "Per-channel normalization: paper, zscore or none")
        ->capture_default_str();
  }
  [[nodiscard]] library::FeatureOptions options() const {
    library::FeatureOptions o{.length = length, .band_fraction = band,
                              .normalization = analysis::parseNormalization(normalization),
                              .timing_weight = timing_weight};
    library::checkFeatureOptions(o);
    return o;
  }
};

/// A query: a profile CSV, or entry:KEY of the library (then left out of what it is compared with).
HapticProfile queryProfile(const std::string& text, const std::string& location) {
  if (text.rfind("entry:", 0) == 0) return library::ProfileLibrary::open(location, true).profile(text.substr(6));
  return io::readProfileCsv(text);
}
std::string queryKey(const std::string& text) { return text.rfind("entry:", 0) == 0 ? text.substr(6) : ""; }

std::optional<std::string> optionalText(const std::string& s) { return s.empty() ? std::nullopt : std::optional(s); }

// ---- Subcommands -----------------------------------------------------------------------------

void addInit(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("init", "Make a new, empty profile library (an SQLite file or a postgresql:// database)");
  auto json = std::make_shared<bool>(false);
  cmd->add_flag("--json", *json, "Print the result as JSON");
  cmd->callback([choice, json] { printChange(ops::libraryInit(choice->resolved()), *json, "made, with"); });
}

void addImport(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* import = lib.add_subcommand("import", "Import a data set of real recordings, labelled");
  import->require_subcommand(1);
  auto* svc = import->add_subcommand("svc2004", "The SVC2004 Task 2 folder: 40 writers, genuine sessions 1 and 2, skilled forgeries");
  struct Opts {
    std::string folder, calibration;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  svc->add_option("FOLDER", o->folder, "Folder of U<writer>S<signature>.TXT files")->required();
  svc->add_option("--calibration", o->calibration, "JSON file overriding calibration fields (docs/file-formats.md)");
  svc->add_flag("--json", o->json, "Print the result as JSON");
  svc->callback([choice, o] {
    const io::TabletCalibration cal =
        o->calibration.empty() ? io::svc2004Calibration() : io::loadCalibration(o->calibration, io::svc2004Calibration());
    printChange(addToLibrary(*choice, [&](const std::string& l) { return ops::libraryImportSvc2004(l, o->folder, cal); }),
                o->json, "imported");
  });
}

void addAdd(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("add", "Add a profile file with its labels, or a study's completed trials (--study)");
  struct Opts {
    std::string profile, study, authenticity = "genuine";
    library::EntryLabels labels;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("PROFILE", o->profile, "Haptic-profile CSV to add");
  cmd->add_option("--study", o->study, "A study file: every completed trial, with its subject, session and mode");
  cmd->add_option("--person", o->labels.person, "Whose skill it is (for an imitation, the person imitated)");
  cmd->add_option("--skill", o->labels.skill, "The skill: a character, \"signature\", a task");
  cmd->add_option("--session", o->labels.session, "The recording session");
  cmd->add_option("--date", o->labels.date, "The recording's date, YYYY-MM-DD");
  cmd->add_option("--authenticity", o->authenticity, "genuine or imitation")->capture_default_str();
  cmd->add_option("--imitator", o->labels.imitator, "Who imitated (an imitation only)");
  cmd->add_option("--mode", o->labels.mode, "The training mode it was recorded under");
  cmd->add_option("--device", o->labels.device, "The device (default: the profile's metadata)");
  cmd->add_option("--key", o->labels.key, "Its unique key (default: PERSON/SKILL/FILE-NAME)");
  cmd->add_flag("--json", o->json, "Print the result as JSON");
  cmd->callback([choice, o] {
    HATTR_THROW_UNLESS(o->profile.empty() != o->study.empty(),
                       "library add: expected a PROFILE file or --study FILE (one of them), got {}",
                       o->profile.empty() ? "neither" : "both");
    if (!o->study.empty()) {
      printChange(addToLibrary(*choice, [&](const std::string& l) { return ops::libraryAddStudy(l, o->study); }), o->json,
                  "added");
      return;
    }
    library::EntryLabels labels = o->labels;
    labels.authenticity = library::parseAuthenticity(o->authenticity, "--authenticity");
    HATTR_THROW_UNLESS(!labels.person.empty() && !labels.skill.empty(),
                       "library add {}: expected --person and --skill, got {}", o->profile,
                       labels.person.empty() ? "no --person" : "no --skill");
    printChange(addToLibrary(*choice, [&](const std::string& l) { return ops::libraryAddProfile(l, o->profile, labels); }),
                o->json, "added");
  });
}

struct FilterFlags {
  std::string person, skill, session, authenticity;
  void add(CLI::App& cmd) {
    cmd.add_option("--person", person, "Only this person's entries");
    cmd.add_option("--skill", skill, "Only this skill's entries");
    cmd.add_option("--session", session, "Only this session's entries");
    cmd.add_option("--authenticity", authenticity, "Only genuine or imitation entries");
  }
  [[nodiscard]] library::EntryFilter filter() const {
    library::EntryFilter f{optionalText(person), optionalText(skill), optionalText(session), std::nullopt};
    if (!authenticity.empty()) f.authenticity = library::parseAuthenticity(authenticity, "--authenticity");
    return f;
  }
};

void addList(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("list", "List the entries (by person, skill, session)");
  auto filter = std::make_shared<FilterFlags>();
  filter->add(*cmd);
  auto json = std::make_shared<bool>(false);
  cmd->add_flag("--json", *json, "Print the entries as JSON");
  cmd->callback([choice, filter, json] {
    const auto opened = library::ProfileLibrary::open(choice->resolved(), true);
    const auto entries = opened.list(filter->filter());
    if (*json) {
      nlohmann::json out = nlohmann::json::array();
      for (const auto& e : entries) out.push_back(ops::libraryEntryJson(e));
      printJson({{"library", opened.location()}, {"entries", out}});
      return;
    }
    std::cout << fmt::format("{:<24} {:<10} {:<12} {:<8} {:<10} {:>8} {:>8}\n", "key", "person", "skill", "session",
                             "kind", "samples", "s");
    for (const auto& e : entries) {
      std::cout << fmt::format("{:<24} {:<10} {:<12} {:<8} {:<10} {:>8} {:>8.2f}\n", e.labels.key, e.labels.person,
                               e.labels.skill, e.labels.session.empty() ? "-" : e.labels.session,
                               library::authenticityName(e.labels.authenticity), e.samples, e.duration_s);
    }
    std::set<std::string> persons;
    for (const auto& e : entries) persons.insert(e.labels.person);
    std::cout << fmt::format("{} entries, {} persons\n", entries.size(), persons.size());
  });
}

void addShow(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("show", "One entry's labels and its profile's summary");
  auto key = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("KEY", *key, "The entry's key")->required();
  cmd->add_flag("--json", *json, "Print the entry as JSON");
  cmd->callback([choice, key, json] {
    const auto opened = library::ProfileLibrary::open(choice->resolved(), true);
    const auto e = opened.entry(*key);
    const HapticProfile p = opened.profile(e.id);
    if (*json) {
      nlohmann::json out = ops::libraryEntryJson(e);
      out["profile"] = ops::profileSummaryJson(p);
      printJson(out);
      return;
    }
    const auto& l = e.labels;
    std::cout << fmt::format("key          {}\nperson       {}\nskill        {}\nsession      {}\ndate         {}\n"
                             "authenticity {}{}\nmode         {}\ndevice       {}\nsource       {}\nadded        {}\n",
                             l.key, l.person, l.skill, l.session.empty() ? "-" : l.session, l.date.empty() ? "-" : l.date,
                             library::authenticityName(l.authenticity), l.imitator.empty() ? "" : " by " + l.imitator,
                             l.mode.empty() ? "-" : l.mode, l.device, l.source, e.added_utc)
              << profileSummaryText(p);
  });
}

void addRemove(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("remove", "Remove entries by key, all or none");
  auto keys = std::make_shared<std::vector<std::string>>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("KEY", *keys, "Keys of the entries")->required();
  cmd->add_flag("--json", *json, "Print the result as JSON");
  cmd->callback([choice, keys, json] { printChange(ops::libraryRemove(choice->resolved(), *keys), *json, "removed"); });
}

void addExport(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("export", "Write entries as profile CSVs with an index, library.csv");
  auto filter = std::make_shared<FilterFlags>();
  filter->add(*cmd);
  struct Opts {
    std::string out;
    bool force = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("-o,--out", o->out, "Folder to write (made whole, or not at all)")->required();
  cmd->add_flag("--force", o->force, "Replace the folder if it exists");
  cmd->add_flag("--json", o->json, "Print the result as JSON");
  cmd->callback([choice, filter, o] {
    printChange(ops::libraryExport(choice->resolved(), filter->filter(), o->out, o->force), o->json,
                fmt::format("exported to {}:", o->out));
  });
}

void addVerify(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("verify", "Is this profile the claimed person's? Score, threshold, decision");
  struct Opts {
    std::string profile, claim, skill, session;
    std::optional<double> threshold;
    MatchFlags match;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("PROFILE", o->profile, "A profile CSV, or entry:KEY of the library")->required();
  cmd->add_option("--claim", o->claim, "The person it claims to be")->required();
  cmd->add_option("--skill", o->skill, "The skill")->required();
  cmd->add_option("--session", o->session, "Enrol only this session's genuine profiles");
  cmd->add_option("--threshold", o->threshold, "Accept at or below this score (default: the one an evaluation saved)");
  o->match.add(*cmd, true);
  cmd->add_flag("--json", o->json, "Print the result as JSON");
  cmd->callback([choice, o] {
    const std::string location = choice->resolved();
    const ops::VerifyOptions v{o->claim, o->skill, optionalText(o->session), library::parseFeatureSet(o->match.features),
                               o->match.options(), library::parseScoreRule(o->match.rule), o->threshold,
                               queryKey(o->profile)};
    const auto r = ops::libraryVerify(location, queryProfile(o->profile, location), v);
    if (o->json) {
      printJson(r.toJson());
      return;
    }
    std::cout << fmt::format("{}: {} as {} ({} features, {} references, spread {:.4g})\nscore {:.4f}, threshold {:.4f} "
                             "({})\n",
                             r.accepted ? "ACCEPTED" : "REJECTED", o->profile, r.claim, r.set, r.references, r.spread,
                             r.score, r.threshold, r.threshold_from);
  });
}

void addIdentify(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("identify", "Whose is this profile? The nearest persons, by exact search");
  struct Opts {
    std::string profile, skill;
    std::size_t top = 5;
    bool brute = false, json = false;
    MatchFlags match;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("PROFILE", o->profile, "A profile CSV, or entry:KEY of the library")->required();
  cmd->add_option("--skill", o->skill, "The skill")->required();
  cmd->add_option("--top", o->top, "How many persons")->capture_default_str();
  cmd->add_flag("--brute-force", o->brute, "Compute every distance in full (the baseline; the same answer)");
  o->match.add(*cmd, true);
  cmd->add_flag("--json", o->json, "Print the result as JSON");
  cmd->callback([choice, o] {
    const std::string location = choice->resolved();
    const ops::IdentifyOptions options{o->skill, library::parseFeatureSet(o->match.features), o->match.options(), o->top,
                                       o->brute, queryKey(o->profile)};
    const auto r = ops::libraryIdentify(location, queryProfile(o->profile, location), options);
    if (o->json) {
      printJson(r.toJson());
      return;
    }
    for (std::size_t i = 0; i < r.ranked.size(); ++i) {
      std::cout << fmt::format("{:>2}. {:<12} {:.4f}  (nearest {})\n", i + 1, r.ranked[i].person, r.ranked[i].distance,
                               r.ranked[i].key);
    }
    std::cout << fmt::format("{} candidates: {} passed the coarse bound, {} of them ruled out by LB_Keogh; {} full "
                             "DTWs, {} abandoned\n",
                             r.stats.candidates, r.stats.lower_bounds, r.stats.pruned_by_keogh, r.stats.dtw_full,
                             r.stats.dtw_abandoned);
  });
}

void addTemplate(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("template", "A person's template for a skill (DTW barycenter averaging) as a profile CSV");
  struct Opts {
    std::string person, skill, out, spread;
    bool force = false, json = false, shape_only = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("--person", o->person, "Whose template")->required();
  cmd->add_option("--skill", o->skill, "Of which skill")->required();
  cmd->add_option("-o,--output", o->out, "Profile CSV to write (a reference like any)")->required();
  cmd->add_option("--spread", o->spread, "CSV of the spread along the template: t_s, spread_mm, force_spread_N");
  cmd->add_flag("--shape-only", o->shape_only, "Align on the shape alone (not on the force profile too)");
  cmd->add_flag("--force", o->force, "Replace the output files if they exist");
  cmd->add_flag("--json", o->json, "Print the template's summary as JSON");
  cmd->callback([choice, o] {
    std::vector<fs::path> outputs{o->out};
    if (!o->spread.empty()) outputs.push_back(o->spread);
    checkOutputFiles(outputs, o->force);
    const std::string reference = fmt::format("library:{}#{}/{}", choice->resolved(), o->person, o->skill);
    const auto t = library::libraryTemplate(reference, {.align_force = !o->shape_only});
    io::writeProfileCsv(t.profile, o->out, o->force ? Overwrite::kReplace : Overwrite::kRefuse);
    if (!o->spread.empty()) {
      io::Table table{{"t_s", "spread_mm", "force_spread_N"}, {}, ""};
      for (std::size_t i = 0; i < t.profile.size(); ++i) {
        table.rows.push_back({fmt::format("{}", t.profile[i].t_s), fmt::format("{}", 1e3 * t.spread_m[i]),
                              fmt::format("{}", t.force_spread_N[i])});
      }
      io::writeTable(table, o->spread, o->force);
    }
    if (o->json) {
      nlohmann::json j = ops::profileSummaryJson(t.profile);
      j["recordings"] = t.recordings;
      j["iterations"] = t.iterations;
      j["reference"] = reference;
      printJson(j);
      return;
    }
    std::cout << fmt::format("template of {} {} from {} recordings ({} DBA iterations) -> {}\n", o->person, o->skill,
                             t.recordings, t.iterations, o->out)
              << profileSummaryText(t.profile);
  });
}

void addEvaluate(CLI::App& lib, std::shared_ptr<LibraryChoice> choice) {
  auto* cmd = lib.add_subcommand("evaluate", "Verification and identification by a stated protocol (svc2004)");
  struct Opts {
    std::string protocol = "svc2004", out, sets;
    library::ProtocolOptions protocol_options;
    MatchFlags match;
    bool json = false, save = false, force = false;
  };
  auto o = std::make_shared<Opts>();
  cmd->add_option("--protocol", o->protocol, "The protocol: svc2004")->capture_default_str();
  cmd->add_option("--seed", o->protocol_options.seed, "Seed of the enrolment and random-forgery draws")->capture_default_str();
  cmd->add_option("--runs", o->protocol_options.runs, "Runs per writer")->capture_default_str();
  cmd->add_option("--sets", o->sets,
                  "Feature sets, comma-separated (default: each of the five alone, shape+force, shape+timing, "
                  "shape+force+timing, all)");
  cmd->add_option("--threads", o->protocol_options.threads, "Threads for the DTWs")->capture_default_str();
  o->match.add(*cmd, false);
  cmd->add_option("-o,--out", o->out, "Folder for the report: report.html (DET figures), results.csv, scores.csv, results.json");
  cmd->add_flag("--force", o->force, "Replace the report folder's files");
  cmd->add_flag("--save-thresholds", o->save, "Save each set's a-priori threshold in the library for `verify`");
  cmd->add_flag("--json", o->json, "Print the results as JSON");
  cmd->callback([choice, o] {
    HATTR_THROW_UNLESS(o->protocol == "svc2004", "--protocol: expected svc2004, got \"{}\"", o->protocol);
    library::ProtocolOptions options = o->protocol_options;
    options.features = o->match.options();
    options.rule = library::parseScoreRule(o->match.rule);
    if (!o->sets.empty()) {
      options.sets.clear();
      std::size_t start = 0;
      while (start <= o->sets.size()) {
        const std::size_t comma = std::min(o->sets.find(',', start), o->sets.size());
        options.sets.push_back(library::parseFeatureSet(std::string_view(o->sets).substr(start, comma - start)));
        start = comma + 1;
      }
    }
    if (!o->out.empty()) report::checkLibraryReportFolder(o->out, o->force);
    const auto result = ops::libraryEvaluate(choice->resolved(), options, o->save);
    if (!o->out.empty()) report::writeLibraryEvaluationReport(result, o->out);
    if (o->json) {
      printJson(report::libraryEvaluationJson(result));
      return;
    }
    std::cout << report::libraryEvaluationText(result);
    if (!o->out.empty()) std::cout << "report: " << (fs::path(o->out) / "report.html").string() << '\n';
  });
}

}  // namespace

void registerLibraryCommands(CLI::App& app) {
  auto* lib = app.add_subcommand("library", "The profile library: persons' haptic profiles, verification, identification");
  lib->require_subcommand(1);
  auto choice = std::make_shared<LibraryChoice>();
  lib->add_option("-L,--library", choice->location,
                  "The library: an SQLite file or a postgresql:// address (default: $HATTR_LIBRARY, else library.sqlite)")
;
  lib->fallthrough();
  addInit(*lib, choice);
  addImport(*lib, choice);
  addAdd(*lib, choice);
  addList(*lib, choice);
  addShow(*lib, choice);
  addRemove(*lib, choice);
  addExport(*lib, choice);
  addVerify(*lib, choice);
  addIdentify(*lib, choice);
  addTemplate(*lib, choice);
  addEvaluate(*lib, choice);
}

}  // namespace hattr::cli
