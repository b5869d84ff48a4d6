// hattr learner plan | list | progress: a learner's practice plans and progress, as the
// studio's Learners tab makes and shows them (ops/practice_plan.hpp, report/learner_progress.hpp).
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/atomic_file.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/ops/practice_plan.hpp"
#include "hattr/report/learner_progress.hpp"

namespace hattr::cli {
namespace {

struct LearnerOptions {
  std::string folder;
  ops::PracticePlanOptions plan;
  int age = 0;
  std::string strategy = "pcontrol";
  std::string db;
  std::string subject;
  std::string html;
  bool pseudonymized = false;
  bool force = false;
  bool json = false;
};

void runPlan(LearnerOptions& opt) {
  if (opt.age > 0) opt.plan.learner.age_years = opt.age;
  opt.plan.strategy = guidance::parseMode(opt.strategy);
  const auto file = ops::createPracticePlan(opt.folder, opt.plan);
  const ops::PracticePlanSummary p = ops::summarizePracticePlan(file, session::localToday());
  if (opt.json) return printJson(ops::toJson(p));
  std::cout << fmt::format("created {}: {} trials planned over {} sessions; {}\n", file.string(), p.trials_total,
                           p.schedule.sessions, session::scheduleText(p.schedule));
}

void runList(const LearnerOptions& opt) {
  std::vector<std::string> skipped;
  const auto plans = ops::listPracticePlans(opt.folder, session::localToday(), &skipped);
  if (opt.json) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& p : plans) out.push_back(ops::toJson(p));
    return printJson({{"folder", opt.folder}, {"plans", out}, {"skipped", skipped}});
  }
  for (const auto& p : plans) {
    std::cout << fmt::format("{:<10} {}  {}, {}: {}/{} trials; {}\n", p.learner.code, p.file.filename().string(),
                             fmt::join(p.letters, " "), guidance::strategyInfo(p.strategy).plain_name,
                             p.trials_completed, p.trials_total, session::scheduleText(p.schedule));
  }
  for (const auto& s : skipped) std::cerr << "hattr: skipped " << s << "\n";
  if (plans.empty()) std::cout << fmt::format("no practice plan in {}\n", opt.folder);
}

void runProgress(const LearnerOptions& opt) {
  if (!opt.html.empty()) checkOutputFiles({opt.html}, opt.force);
  const auto db = session::StudyDatabase::open(opt.db, session::OpenMode::kReadOnly);
  const report::LearnerProgress progress = report::learnerProgress(db, opt.subject);
  if (!opt.html.empty()) {
    writeFileAtomically(opt.html,
                        report::progressPageHtml(progress, {.identified = !opt.pseudonymized,
                                                            .printed = session::localToday().iso()}),
                        opt.force ? Overwrite::kReplace : Overwrite::kRefuse);
  }
  if (opt.json) return printJson(report::toJson(progress));
  for (const auto& s : progress.sessions) std::cout << s.sentence << "\n";
  std::cout << progress.next << "\n";
}

}  // namespace

void registerLearnerCommands(CLI::App& app) {
  auto* learner = app.add_subcommand("learner", "One learner's practice plans and progress (the studio's Learners tab)");
  learner->require_subcommand(1);
  auto opt = std::make_shared<LearnerOptions>();

  auto* plan = learner->add_subcommand("plan", "Make a practice plan for a learner: FOLDER/CODE/plan-N.sqlite");
  plan->add_option("--folder", opt->folder, "Practice folder (one folder per learner)")->required();
  plan->add_option("--code", opt->plan.learner.code, "The learner's code (names their files and exports)")->required();
  plan->add_option("--name", opt->plan.learner.name, "Their name (left out of exports unless --identified)");
  plan->add_option("--age", opt->age, "Age in years")->check(CLI::Range(1, 120));
  plan->add_option("--handedness", opt->plan.learner.handedness, "right, left or both");
  plan->add_option("--notes", opt->plan.learner.notes, "Notes (left out of exports unless --identified)");
  plan->add_option("--letters", opt->plan.letters, "Letters to practise: characters (a A 7), glyph names or .json files")
      ->required()
      ->delimiter(',');
  plan->add_option("--strategy", opt->strategy, "Training strategy (`hattr strategies`)")->capture_default_str();
  plan->add_option("--sessions", opt->plan.sessions, "Practice sessions")->capture_default_str();
  plan->add_option("--trials", opt->plan.trials_per_session, "Guided trials per letter and session")->capture_default_str();
  plan->add_option("--checks", opt->plan.check_trials, "Trials written alone per letter at each session's end")->capture_default_str();
  plan->add_option("--days-between", opt->plan.days_between, "Days from one session to the next")->capture_default_str();
  plan->add_option("--retention-days", opt->plan.retention_after_days,
                   "A last check this many days after the last session (0: none)")
      ->capture_default_str();
  plan->add_option("--rest", opt->plan.rest_s, "Rest between trials [s]")->capture_default_str();
  plan->add_option("--device", opt->plan.device, "The pen")->capture_default_str();
  plan->add_flag("--json", opt->json, "Print the plan's summary as JSON");
  plan->callback([opt] { runPlan(*opt); });

  auto* list = learner->add_subcommand("list", "The practice plans in a folder, each learner's next session");
  list->add_option("--folder", opt->folder, "Practice folder")->required();
  list->add_flag("--json", opt->json, "Print JSON");
  list->callback([opt] { runList(*opt); });

  auto* progress = learner->add_subcommand("progress", "A learner's progress: one sentence a session, or the printable page");
  progress->add_option("--db", opt->db, "The plan (any study database)")->required();
  progress->add_option("--subject", opt->subject, "The learner's code (needed when the study has several)");
  progress->add_option("--html", opt->html, "Write the printable page (self-contained HTML) here");
  progress->add_flag("--pseudonymized", opt->pseudonymized, "The page names the learner by code only, without notes");
  progress->add_flag("--force", opt->force, "Replace an existing --html file");
  progress->add_flag("--json", opt->json, "Print JSON");
  progress->callback([opt] { runProgress(*opt); });
}

}  // namespace hattr::cli
