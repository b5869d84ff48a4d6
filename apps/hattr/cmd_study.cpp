// hattr study init|run|status|export|import|push|analyze|report|example: training studies in a crash-safe database.

#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/ops/study_run.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/report/paper_comparison.hpp"
#include "hattr/report/study_report.hpp"
#include "hattr/session/study_export.hpp"
#include "hattr/session/study_schedule.hpp"
#include "hattr/sim/expert.hpp"

namespace hattr::cli {
namespace {

struct StudyOptions {
  std::string study_file;
  std::string db;
  std::string subject;
  std::string out;
  std::string from;
  std::string clock = "sim";
  int max_trials = -1;
  int subjects_at_once = 1;
  double lease_timeout_s = 30.0;
  double band = -1.0;
  std::string days = "sim";
  std::string design;
  bool list = false;
  bool json = false;
  bool quiet = false;
  bool force = false;
  bool identified = false;
};

nlohmann::json statusJson(const session::StudyDatabase& db) {
  nlohmann::json subjects = nlohmann::json::array();
  int total = 0, completed = 0, interrupted = 0, running = 0;
  // A trial marked running is being run while a runner holds the study; otherwise its runner died.
  const bool runner_active = db.runnerActive();
  const session::LocalDate today = session::localToday();
  for (const auto& s : db.subjects()) {
    const auto trials = db.trials(s.id);
    int done = 0;
    for (const auto& t : trials) {
      done += t.status == session::TrialStatus::kCompleted ? 1 : 0;
      const int now_running = t.status == session::TrialStatus::kRunning ? 1 : 0;
      running += runner_active ? now_running : 0;
      interrupted += t.interruptions + (runner_active ? 0 : now_running);
    }
    nlohmann::json order = nlohmann::json::array();
    for (const auto m : s.mode_order) order.push_back(std::string(guidance::modeName(m)));
    nlohmann::json next = nullptr;
    if (const auto n = db.nextTrial(s.id)) {
      next = {{"sequence", n->plan.sequence}, {"mode", std::string(guidance::modeName(n->plan.mode))},
              {"phase", n->plan.phase}, {"trial", n->plan.index}, {"skill", n->plan.skill},
              {"session", n->plan.session + 1}, {"block", n->plan.block + 1},
              {"status", std::string(session::trialStatusName(n->status))}};
    }
    subjects.push_back({{"id", s.id}, {"participant", s.spec.participant}, {"group", s.spec.group},
                        {"mode_order", order}, {"trials", trials.size()}, {"completed", done}, {"next", next},
                        {"schedule", ops::scheduleJson(session::subjectSchedule(db.study(), trials, today))}});
    total += static_cast<int>(trials.size());
    completed += done;
  }
  nlohmann::json groups = nlohmann::json::array();
  for (const auto& g : db.study().groups) groups.push_back(g.name);
  return {{"study", db.study().name}, {"file", db.file().string()}, {"schema_version", db.schemaVersion()},
          {"paper_design", session::isPaperDesign(db.study())}, {"groups", groups},
          {"sessions", db.study().schedule.size()}, {"today", today.iso()}, {"subjects", subjects}, {"trials_total", total}, {"trials_completed", completed},
          {"trials_interrupted", interrupted}, {"trials_running", running}, {"runner_active", runner_active}};
}

void runInit(const StudyOptions& opt) {
  session::StudyDefinition study = session::loadStudy(opt.study_file);
  sim::recordNamedExperts(study);  // experts named by their glyph ("na", "ந")
  // An expert the device cannot render is refused before anything is made (issue 38).
  if (!session::checkExpertsRenderable(study)) {
    std::cerr << fmt::format("hattr: the experts were not checked against {}: its limits are known once it is opened "
                             "(`hattr devices check {}`)\n",
                             study.device, study.device);
  }
  const session::StudyDatabase db = session::StudyDatabase::create(opt.db, study);
  const auto status = statusJson(db);
  if (opt.json) return printJson(status);
  std::cout << fmt::format("created {}: {} subjects, {} trials planned\n", opt.db, study.subjects.size(),
                           status["trials_total"].get<int>());
}

// The library's run, with a progress line on a terminal: the subject's trial just done.
void runRun(const StudyOptions& opt) {
  ops::StudyRunOptions run{.db = opt.db,
                           .subject = opt.subject,
                           .clock = session::parseClock(opt.clock),
                           .max_trials = opt.max_trials,
                           .subjects_at_once = opt.subjects_at_once,
                           .lease_timeout_s = opt.lease_timeout_s,
                           .follow_calendar = opt.days == "calendar"};
  Progress progress("study run", 0, "trials");
  int done = 0;
  if (!opt.quiet) {
    run.started = [&progress](int trials_to_run) { progress.stage("study run", trials_to_run); };
    run.progress = [&progress, &done](const session::RunProgress& p) {
      progress.update(++done, fmt::format("study run: {} {:>2}/{} {} {} {:>2}", p.subject, p.completed, p.total,
                                          guidance::modeName(p.trial->plan.mode), p.trial->plan.phase,
                                          p.trial->plan.index));
    };
  }
  const ops::StudyRunResult result = ops::runStudy(run);
  progress.finish();
  if (opt.json) {
    return printJson(statusJson(session::StudyDatabase::open(opt.db, session::OpenMode::kReadOnly)));
  }
  std::cout << fmt::format("ran {} trial{}\n", result.trials_run, result.trials_run == 1 ? "" : "s");
  for (const auto& w : result.waiting) {
    std::cout << fmt::format("  {} waits: {}\n", w.subject, session::scheduleText(w.schedule));
  }
}

void runStatus(const StudyOptions& opt) {
  const session::StudyDatabase db = session::StudyDatabase::open(opt.db, session::OpenMode::kReadOnly);
  const auto status = statusJson(db);
  if (opt.json) return printJson(status);
  std::cout << fmt::format("{} ({}): {}/{} trials completed, {} interrupted{}\n", status["study"].get<std::string>(), opt.db,
                           status["trials_completed"].get<int>(), status["trials_total"].get<int>(),
                           status["trials_interrupted"].get<int>(),
                           status["runner_active"].get<bool>()
                               ? fmt::format(", {} running now (a runner holds the study)", status["trials_running"].get<int>())
                               : "");
  const bool design = !status["paper_design"].get<bool>();
  for (const auto& s : status["subjects"]) {
    std::string next = "done";
    if (!s["next"].is_null()) {
      next = fmt::format("next: {} {} {}", s["next"]["mode"].get<std::string>(), s["next"]["phase"].get<std::string>(),
                         s["next"]["trial"].get<int>());
    }
    // A design says each subject's group and where it stands in the schedule.
    const std::string where = design ? fmt::format("group {}  {}", s["group"].get<std::string>(),
                                                   s["schedule"]["text"].get<std::string>())
                                     : fmt::format("order {}  {}", s["mode_order"].dump(), next);
    std::cout << fmt::format("  {:<8} {:>3}/{:<3} {}\n", s["id"].get<std::string>(), s["completed"].get<int>(),
                             s["trials"].get<int>(), where);
  }
}

void runExport(const StudyOptions& opt) {
  const session::StudyDatabase db = session::StudyDatabase::open(opt.db, session::OpenMode::kReadOnly);
  const std::size_t n = session::exportStudy(db, opt.out, {.identified = opt.identified});
  std::cout << fmt::format("exported {} trial profiles to {}/{}\n", n, opt.out,
                           opt.identified ? " (with learners' names and notes)" : "");
}

/// The analysis options, scoring progress drawn on `progress` (a terminal only).
report::AnalysisOptions analysisOptions(const StudyOptions& opt, Progress& progress) {
  report::AnalysisOptions a;
  a.band_fraction = opt.band;
  a.progress = [&progress](int scored, int total) {
    if (scored == 0) progress.stage(progress.label(), total);
    progress.update(scored);
  };
  return a;
}

/// A study of groups and sessions (not the paper's design): its own analysis and report.
void runDesignAnalysis(const StudyOptions& opt, session::StudyDatabase& db, bool report) {
  std::vector<std::string> outputs = report::kDesignCsvFiles;
  if (report) outputs.insert(outputs.end(), report::kStudyReportFiles.begin(), report::kStudyReportFiles.end());
  if (!opt.out.empty()) checkOutputFolder(opt.out, outputs, opt.force);  // before anything is written
  Progress progress(report ? "study report: scoring trials" : "scoring trials", 0, "trials");
  const report::DesignAnalysis analysis = report::analyzeDesign(db, analysisOptions(opt, progress));
  progress.finish();
  if (!opt.json) std::cout << "analysis: " << analysis.reason << '\n';
  const nlohmann::json json = report::designAnalysisToJson(analysis);
  db.putResult("design_analysis", json.dump());
  if (!opt.out.empty()) report::writeDesignCsv(analysis, opt.out);
  if (report) {
    const auto html = report::writeDesignReport(db, analysis, opt.out);
    std::cout << fmt::format("report: {} (and report.md, figures/, CSV tables beside it)\n", html.string());
  } else if (opt.json) {
    return printJson(json);
  } else {
    std::cout << fmt::format("analyzed {} completed trials of {} ({} planned); results stored in the database{}\n",
                             analysis.scores.size(), opt.db, analysis.trials_planned,
                             opt.out.empty() ? "" : fmt::format(" and written to {}/", opt.out));
  }
  for (const auto& line : report::designConclusions(analysis)) std::cout << "  " << line << '\n';
}

/// Every trial of a paper's study in the long table (trials.csv): its training trials scored
/// now, its recall trials as the balanced analysis scored them.
void writePaperTrialsCsv(const StudyOptions& opt, const session::StudyDatabase& db, const report::StudyAnalysis& analysis) {
  Progress progress("scoring every trial for trials.csv", 0, "trials");
  report::writeTrialsCsv(db, analysis, analysisOptions(opt, progress), std::filesystem::path(opt.out) / "trials.csv");
  progress.finish();
}

void runAnalyze(const StudyOptions& opt) {
  session::StudyDatabase db = session::StudyDatabase::open(opt.db, session::OpenMode::kReadWrite);
  if (!report::chooseAnalysis(db).balanced) return runDesignAnalysis(opt, db, false);
  if (!opt.out.empty()) checkOutputFolder(opt.out, report::kAnalysisCsvFiles, opt.force);  // before anything is written
  Progress progress("scoring recall trials", 0, "trials");
  const report::StudyAnalysis analysis = report::analyzeStudy(db, analysisOptions(opt, progress));
  progress.finish();
  report::storeAnalysis(db, analysis);
  if (!opt.out.empty()) {
    report::writeAnalysisCsv(analysis, opt.out);
    writePaperTrialsCsv(opt, db, analysis);
  }
  if (opt.json) return printJson(report::analysisToJson(analysis));
  std::cout << fmt::format("analyzed {} recall trials of {}; results stored in the database{}\n", analysis.costs.size(),
                           opt.db, opt.out.empty() ? "" : fmt::format(" and written to {}/", opt.out));
  for (const auto& line : report::conclusions(analysis)) std::cout << "  " << line << '\n';
}

void runReport(const StudyOptions& opt) {
  session::StudyDatabase db = session::StudyDatabase::open(opt.db, session::OpenMode::kReadWrite);
  if (!report::chooseAnalysis(db).balanced) return runDesignAnalysis(opt, db, true);
  // Every output checked before anything is written (the database's stored analysis included).
  std::vector<std::string> outputs = report::kAnalysisCsvFiles;
  outputs.insert(outputs.end(), report::kStudyReportFiles.begin(), report::kStudyReportFiles.end());
  checkOutputFolder(opt.out, outputs, opt.force);
  Progress progress("study report: scoring recall trials", 0, "trials");
  const report::StudyAnalysis analysis = report::analyzeStudy(db, analysisOptions(opt, progress));
  report::storeAnalysis(db, analysis);
  report::writeAnalysisCsv(analysis, opt.out);
  progress.stage("study report: writing the report and figures", 0);
  const auto html = report::writeStudyReport(db, analysis, opt.out);
  progress.finish();
  writePaperTrialsCsv(opt, db, analysis);
  std::cout << fmt::format("report: {} (and report.md, figures/, CSV tables beside it)\n", html.string());
  const report::PaperComparison paper = report::compareWithPaper(db.study(), db.subjects().size(), analysis);
  for (const auto& line : report::comparisonText(paper)) std::cout << line << '\n';
}

void runPush(const StudyOptions& opt) {
  const session::StudyDatabase from = session::StudyDatabase::open(opt.from, session::OpenMode::kReadOnly);
  session::StudyDatabase to = session::StudyDatabase::open(opt.db, session::OpenMode::kReadWrite);
  const auto pushed = to.pushFrom(from);
  if (opt.json) {
    return printJson({{"from", opt.from}, {"to", opt.db}, {"pushed", pushed.pushed}, {"subjects", pushed.subjects},
                      {"already_there", pushed.already_there}});
  }
  std::cout << fmt::format("pushed {} trial{} of {} subject{} from {} to {}; {} already there\n", pushed.pushed,
                           pushed.pushed == 1 ? "" : "s", pushed.subjects, pushed.subjects == 1 ? "" : "s", opt.from,
                           opt.db, pushed.already_there);
}

void runImport(const StudyOptions& opt) {
  const std::size_t n = session::importStudy(opt.from, opt.db);
  std::cout << fmt::format("imported {} trials into {}\n", n, opt.db);
}

// study init and study run: create a study database, run its unfinished trials.
void addStudyRunCommands(CLI::App* study, const std::shared_ptr<StudyOptions>& opt) {
  auto* init = study->add_subcommand("init", "Create a study database from a study file (see `hattr study example`)");
  init->add_option("STUDY", opt->study_file, "Study definition (JSON)")->required();
  init->add_option("--db", opt->db, "Study database to create: a file, or an empty PostgreSQL database "
                   "(postgresql://[user@]host/db, no password: see docs/study-store.md)")->required();
  init->add_flag("--json", opt->json, "Print the status as JSON");
  init->callback([opt] { runInit(*opt); });

  auto* run = study->add_subcommand("run", "Run the unfinished trials, resuming where the study stopped");
  run->add_option("--db", opt->db, "Study database")->required();
  run->add_option("--subject", opt->subject, "Run only this subject");
  run->add_option("--clock", opt->clock, "sim: simulated time; real: the real-time loop")
      ->check(CLI::IsMember({"sim", "real"}))
      ->capture_default_str();
  run->add_option("--max-trials", opt->max_trials, "Stop after this many trials");
  run->add_option("--subjects-at-once", opt->subjects_at_once,
                  "Simulated subjects run at once on their own threads (the sim:// pen, --clock sim, all subjects, "
                  "no --max-trials, no mentor; otherwise one at a time); the trials are the same to the bit")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  run->add_option("--lease-timeout", opt->lease_timeout_s,
                  "PostgreSQL stations: seconds after which a station that stopped renewing its subjects' leases "
                  "loses them to another station")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  run->add_option("--days", opt->days,
                  "sim: a session on a later day follows at once (the simulated trainee is told the days passed); "
                  "calendar: it waits for its date, and the subjects left are listed")
      ->check(CLI::IsMember({"sim", "calendar"}))
      ->capture_default_str();
  run->add_flag("--quiet", opt->quiet, "No progress line");
  run->add_flag("--json", opt->json, "Print the status as JSON when done");
  run->callback([opt] { runRun(*opt); });
}

// study status, export, import and push: what a study database holds, and moving it.
void addStudyDataCommands(CLI::App* study, const std::shared_ptr<StudyOptions>& opt) {
  auto* status = study->add_subcommand("status", "Trials completed and interrupted, and each subject's next trial");
  status->add_option("--db", opt->db, "Study database")->required();
  status->add_flag("--json", opt->json,
                   "Print JSON: subjects [{id, group, mode_order, trials, completed, next, schedule}], trials_total, "
                   "trials_completed, trials_interrupted");
  status->callback([opt] { runStatus(*opt); });

  auto* exp = study->add_subcommand("export", "Write the study as files: definition, experts, trials table, one CSV per trial");
  exp->add_option("--db", opt->db, "Study database")->required();
  exp->add_option("--out", opt->out, "Folder to create")->required();
  exp->add_flag("--identified", opt->identified,
                "Keep learners' names and notes in study.json (left out by default: learners are named by their code)");
  exp->callback([opt] { runExport(*opt); });

  auto* imp = study->add_subcommand("import", "Create a study database from an export folder");
  imp->add_option("FOLDER", opt->from, "Export folder")->required();
  imp->add_option("--db", opt->db, "Study database to create")->required();
  imp->callback([opt] { runImport(*opt); });

  auto* push = study->add_subcommand("push", "Copy a study's completed trials into the same study elsewhere (a "
                                     "station's file run offline, into the lab's PostgreSQL study); idempotent");
  push->add_option("--from", opt->from, "Study database to copy from")->required();
  push->add_option("--to", opt->db, "Study database to copy into (the same study, made from the same study file)")
      ->required();
  push->add_flag("--json", opt->json, "Print JSON: pushed, subjects, already_there");
  push->callback([opt] { runPush(*opt); });
}

// study analyze, report and example: the analysis, the report, the shipped designs.
void addStudyAnalysisCommands(CLI::App* study, const std::shared_ptr<StudyOptions>& opt) {
  auto* analyze = study->add_subcommand(
      "analyze", "The paper's design: DTW costs of every recall trial against the expert, ANOVAs, Tukey HSD and Table 1. "
                 "Any other design: every completed trial's costs, learning curves, retention and transfer. Stored in "
                 "the database");
  analyze->add_option("--db", opt->db, "Study database")->required();
  analyze->add_option("--out", opt->out, "Also write the tables here (the paper's design: recall_costs.csv, anova.csv, "
                      "table1.csv, trials.csv; any other: trials.csv, curves.csv, phases.csv, retention.csv, transfer.csv, models.csv, curve_fits.csv)");
  analyze->add_flag("--force", opt->force, "Replace earlier tables in --out");
  analyze->add_option("--band", opt->band, "Sakoe–Chiba band fraction for DTW (default: none, the paper's)")
      ->check(CLI::Range(0.0, 1.0));
  analyze->add_flag("--json", opt->json, "Print the whole analysis as JSON");
  analyze->callback([opt] { runAnalyze(*opt); });

  auto* rep = study->add_subcommand("report", "Analyze and write report.html (self-contained) and report.md with figures");
  rep->add_option("--db", opt->db, "Study database")->required();
  rep->add_option("--out", opt->out, "Folder for the report")->required();
  rep->add_flag("--force", opt->force, "Replace an earlier report in --out");
  rep->add_option("--band", opt->band, "Sakoe–Chiba band fraction for DTW (default: none)")->check(CLI::Range(0.0, 1.0));
  rep->callback([opt] { runReport(*opt); });

  auto* example = study->add_subcommand("example", "Print a shipped study design (default: the paper's)");
  example->add_flag("--list", opt->list, "List the shipped designs, one a line: name, then the question it answers");
  example->add_option("--design", opt->design, "Print the design called NAME (see --list)");
  example->callback([opt] {
    if (opt->list) {
      for (const auto& d : session::exampleDesigns()) std::cout << fmt::format("{:<18} {}\n", d.name, d.answers);
      return;
    }
    std::cout << (opt->design.empty() ? session::exampleStudyJson() : std::string(session::exampleDesign(opt->design).json));
  });
}

}  // namespace

void registerStudyCommands(CLI::App& app) {
  auto* study = app.add_subcommand("study", "Training studies: the paper's protocol in a crash-safe study database");
  study->require_subcommand(1);
  auto opt = std::make_shared<StudyOptions>();
  addStudyRunCommands(study, opt);
  addStudyDataCommands(study, opt);
  addStudyAnalysisCommands(study, opt);
}

}  // namespace hattr::cli
