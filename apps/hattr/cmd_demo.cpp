// hattr demo: the paper's whole experiment in silico — simulated expert and trainees through
// the real servo loop, paper, guidance, study runner, database, analysis and report.

#include <algorithm>
#include <chrono>
#include <iostream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/report/paper_comparison.hpp"
#include "hattr/report/study_report.hpp"
#include "hattr/sim/in_silico.hpp"

namespace hattr::cli {
namespace {

struct DemoOptions {
  std::string out_dir = "demo-out";
  int subjects = 10;
  std::uint64_t seed = 1;
  bool json = false;
};

const analysis::AnovaRow* row(const analysis::AnovaTable& t, const std::string& source) {
  for (const auto& r : t.rows) {
    if (r.source == source) return &r;
  }
  return nullptr;
}

void runDemo(const DemoOptions& opt) {
  const auto start = std::chrono::steady_clock::now();
  std::cout << fmt::format("hattr demo: the paper's study in silico — {} simulated subjects learn 'Na' (ந) in BASIC, "
                           "PCONTROL and ALPHA,\n11 training + 11 recall trials per mode, through the real servo loop "
                           "at 1 kHz (simulated time).\n\n",
                           opt.subjects);
  sim::InSilicoOptions options{.out_dir = opt.out_dir, .subjects = opt.subjects, .seed = opt.seed};
  Progress progress("hattr demo", 0, "trials");
  if (!opt.json) options.progress = stageProgress(progress, "hattr demo");
  const sim::InSilicoResult r = sim::runInSilicoStudy(options);
  progress.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::uint64_t ticks = r.servo_ticks + static_cast<std::uint64_t>(r.trials) * 300;  // + each trial's settle

  const auto& a = r.analysis;
  const session::StudyDatabase db = session::StudyDatabase::open(r.database, session::OpenMode::kReadOnly);
  const report::PaperComparison paper = report::compareWithPaper(db.study(), db.subjects().size(), a);
  if (opt.json) {
    nlohmann::json json = report::analysisToJson(a);
    json.erase("recall_costs");
    json["database"] = r.database.string();
    json["report"] = r.report_html.string();
    json["trials"] = r.trials;
    json["servo_ticks"] = ticks;
    json["seconds"] = seconds;
    json["paper_comparison"] = report::comparisonToJson(paper);
    return printJson(json);
  }
  // Table 1 and the ANOVA p-values.
  std::cout << fmt::format("\nTable 1: each subject's best mode (lowest mean recall DTW cost)\n{:<8} {:<12} {:<12}\n", "subject",
                           "trajectory", "force");
  for (const auto& [subject, mode] : a.trajectory.best_mode) {
    std::cout << fmt::format("{:<8} {:<12} {:<12}\n", subject, mode, a.force.best_mode.at(subject));
  }
  std::cout << "\nANOVA p-values (mode × subject, subject random; per mode: trial × subject)\n";
  for (const auto* m : {&a.trajectory, &a.force}) {
    const auto* mode = row(m->overall, "mode");
    const auto* subject = row(m->overall, "subject");
    std::cout << fmt::format("  {:<11} mode p = {:.4g}, subject p = {:.4g}", m->metric, mode ? mode->p : NAN,
                             subject ? subject->p : NAN);
    for (const auto& [name, table] : m->per_mode) {
      const auto* trial = row(table, "trial");
      std::cout << fmt::format(", {} trial p = {:.3g}", name, trial ? trial->p : NAN);
    }
    std::cout << '\n';
  }
  std::cout << "\nConclusions\n";
  for (const auto& line : report::conclusions(a)) std::cout << "  - " << line << '\n';
  std::cout << '\n';
  for (const auto& line : report::comparisonText(paper)) std::cout << line << '\n';
  std::cout << fmt::format("\n{} trials, {:.2f} M servo ticks, {:.1f} s.\nReport: {}\nStudy database: {}\n", r.trials,
                           static_cast<double>(ticks) * 1e-6, seconds, r.report_html.string(), r.database.string());
}

}  // namespace

void registerDemoCommand(CLI::App& app) {
  auto opt = std::make_shared<DemoOptions>();
  auto* demo = app.add_subcommand("demo", "Run the paper's study in silico end to end and write the report");
  demo->add_option("--out", opt->out_dir, "Folder for the expert, the study database and the report")->capture_default_str();
  demo->add_option("--subjects", opt->subjects, "Simulated subjects")->check(CLI::Range(2, 1000))->capture_default_str();
  demo->add_option("--seed", opt->seed, "Seed of the simulated subjects")->capture_default_str();
  demo->add_flag("--json", opt->json, "Print the analysis as JSON (no progress bar)");
  demo->callback([opt] { runDemo(*opt); });
}

}  // namespace hattr::cli
