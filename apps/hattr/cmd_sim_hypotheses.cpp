// hattr sim compare-hypotheses: the paper's study under each learning hypothesis, its findings
// point by point, and an A/A check per hypothesis (docs/simulation.md, "Learning hypotheses").

#include <algorithm>
#include <iostream>
#include <memory>
#include <sstream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/report/paper_comparison.hpp"
#include "hattr/sim/in_silico.hpp"

namespace hattr::cli {
namespace {

struct HypothesesOptions {
  std::string hypotheses = "position-plan,force-plan,guidance-dependent";
  int subjects = 10;
  int trials = 11;
  std::uint64_t seed = 1;
  int aa_seeds = 3;
  int threads = 0;
  std::string out_dir = "hypotheses-out";
  bool json = false;
};

/// One hypothesis's results: the paper's study, and its A/A studies.
struct HypothesisResult {
  sim::LearningHypothesis hypothesis;
  report::PaperComparison comparison;
  double p_mode_trajectory = 0.0;
  double p_mode_force = 0.0;
  int aa_significant_trajectory = 0;
  int aa_significant_force = 0;
  std::vector<double> aa_p_trajectory;  ///< the A/A studies' mode-effect p, in seed order
  std::vector<double> aa_p_force;
};

std::vector<sim::LearningHypothesis> parseHypothesisList(const std::string& text) {
  std::vector<sim::LearningHypothesis> out;
  std::stringstream in(text);
  for (std::string name; std::getline(in, name, ',');) {
    const auto h = sim::parseHypothesis(name, "--hypotheses");
    HATTR_THROW_UNLESS(std::find(out.begin(), out.end(), h) == out.end(), "--hypotheses: \"{}\" is given twice", name);
    out.push_back(h);
  }
  HATTR_THROW_UNLESS(!out.empty(), "--hypotheses: expected at least one hypothesis, got \"{}\"", text);
  return out;
}

double modeP(const report::MetricResult& metric) { return metric.overall.row("mode").p; }

/// Runs the paper's study and the A/A studies of one hypothesis; `studies_done` counts studies.
HypothesisResult runHypothesis(const HypothesesOptions& o, sim::LearningHypothesis h, Progress& progress, int& studies_done) {
  const std::string name(sim::hypothesisName(h));
  const auto within = [&progress, &studies_done](std::string_view stage, int done, int total) {
    if (stage == "trials" && total > 0) progress.update(studies_done + static_cast<double>(done) / total);
  };
  HypothesisResult result{.hypothesis = h};
  progress.update(studies_done, fmt::format("{}: the paper's study", name));
  const auto study = sim::runInSilicoStudy({.out_dir = fmt::format("{}/{}", o.out_dir, name), .subjects = o.subjects,
                                            .seed = o.seed, .training_trials = o.trials, .recall_trials = o.trials,
                                            .hypothesis = h, .write_report = false, .threads = o.threads,
                                            .progress = within});
  ++studies_done;
  result.comparison = report::compareWithPaper(study.study, static_cast<std::size_t>(o.subjects), study.analysis);
  result.p_mode_trajectory = modeP(study.analysis.trajectory);
  result.p_mode_force = modeP(study.analysis.force);
  // A/A: the same design with guidance off in every mode, other seeds.
  for (int k = 1; k <= o.aa_seeds; ++k) {
    progress.update(studies_done, fmt::format("{}: A/A study {} of {}", name, k, o.aa_seeds));
    const auto aa = sim::runInSilicoStudy({.out_dir = fmt::format("{}/{}-aa-{:03}", o.out_dir, name, k),
                                           .subjects = o.subjects, .seed = o.seed + static_cast<std::uint64_t>(k),
                                           .training_trials = o.trials, .recall_trials = o.trials, .guidance = false,
                                           .hypothesis = h, .write_report = false, .threads = o.threads,
                                           .progress = within});
    ++studies_done;
    result.aa_p_trajectory.push_back(modeP(aa.analysis.trajectory));
    result.aa_p_force.push_back(modeP(aa.analysis.force));
    result.aa_significant_trajectory += result.aa_p_trajectory.back() < 0.05 ? 1 : 0;
    result.aa_significant_force += result.aa_p_force.back() < 0.05 ? 1 : 0;
  }
  return result;
}

nlohmann::json toJson(const HypothesesOptions& o, const std::vector<HypothesisResult>& results) {
  nlohmann::json hypotheses = nlohmann::json::array();
  for (const auto& r : results) {
    nlohmann::json points = nlohmann::json::array();
    for (const auto& row : r.comparison.rows) {
      points.push_back({{"point", row.point}, {"source", row.source}, {"paper", row.paper}, {"hattr", row.hattr},
                        {"agreement", report::agreementName(row.agreement)}});
    }
    hypotheses.push_back({{"hypothesis", sim::hypothesisName(r.hypothesis)},
                          {"agrees", r.comparison.count(report::Agreement::kAgrees)},
                          {"differs", r.comparison.count(report::Agreement::kDiffers)},
                          {"p_mode_trajectory", r.p_mode_trajectory},
                          {"p_mode_force", r.p_mode_force},
                          {"aa", {{"seeds", o.aa_seeds},
                                  {"significant_trajectory", r.aa_significant_trajectory},
                                  {"significant_force", r.aa_significant_force},
                                  {"p_mode_trajectory", r.aa_p_trajectory},
                                  {"p_mode_force", r.aa_p_force}}},
                          {"points", points}});
  }
  return {{"subjects", o.subjects}, {"training_trials", o.trials}, {"recall_trials", o.trials}, {"seed", o.seed},
          {"alpha", 0.05}, {"hypotheses", hypotheses}};
}

/// `text` cut to `width` characters (UTF-8 code points), ending in "..." when cut (width > 3).
std::string cut(const std::string& text, std::size_t width) {
  const auto isLead = [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; };
  if (static_cast<std::size_t>(std::count_if(text.begin(), text.end(), isLead)) <= width) return text;
  std::size_t chars = 0;
  std::size_t end = 0;
  for (; end < text.size(); ++end) {
    if (isLead(text[end]) && chars++ == width - 3) break;
  }
  return text.substr(0, end) + "...";
}

/// The table: one row per point of the paper, one column per hypothesis.
void printTable(const HypothesesOptions& o, const std::vector<HypothesisResult>& results) {
  std::cout << fmt::format("The paper's study under each learning hypothesis ({} subjects, {}+{} trials per mode, "
                           "seed {}; a point agrees when the study reaches the paper's statement at α = 0.05):\n\n",
                           o.subjects, o.trials, o.trials, o.seed);
  const auto& rows = results.front().comparison.rows;
  std::size_t point_width = 5;
  for (const auto& row : rows) point_width = std::max(point_width, row.point.size());
  constexpr std::size_t kPaperWidth = 28;
  const auto line = [&](const std::string& point, const std::string& paper, const auto& cell) {
    std::string text = fmt::format("{:<{}} {:<{}}", point, point_width, cut(paper, kPaperWidth), kPaperWidth);
    for (const auto& r : results) text += fmt::format(" {:<19}", cell(r));
    std::cout << text << "\n";
  };
  line("point", "the paper", [](const HypothesisResult& r) { return std::string(sim::hypothesisName(r.hypothesis)); });
  for (std::size_t i = 0; i < rows.size(); ++i) {
    line(rows[i].point, rows[i].paper,
         [i](const HypothesisResult& r) { return std::string(report::agreementName(r.comparison.rows[i].agreement)); });
  }
  std::cout << "\n";
  line(fmt::format("points that agree (of {})", rows.size()), "",
       [](const HypothesisResult& r) { return std::to_string(r.comparison.count(report::Agreement::kAgrees)); });
  line("mode effect on shape: p", "", [](const HypothesisResult& r) { return fmt::format("{:.3g}", r.p_mode_trajectory); });
  line("mode effect on haptic profile: p", "",
       [](const HypothesisResult& r) { return fmt::format("{:.3g}", r.p_mode_force); });
  line(fmt::format("A/A: mode effect p < 0.05 (shape, force) of {}", o.aa_seeds), "", [](const HypothesisResult& r) {
    return fmt::format("{}, {}", r.aa_significant_trajectory, r.aa_significant_force);
  });
}

void runHypotheses(const HypothesesOptions& o) {
  const auto hypotheses = parseHypothesisList(o.hypotheses);
  const int studies = static_cast<int>(hypotheses.size()) * (1 + o.aa_seeds);
  Progress progress("hypotheses", studies, "studies");
  int studies_done = 0;
  std::vector<HypothesisResult> results;
  for (const auto h : hypotheses) results.push_back(runHypothesis(o, h, progress, studies_done));
  progress.finish();
  HATTR_DEMAND(results.front().comparison.applicable, "the paper's study is not comparable with the paper");
  if (o.json) return printJson(toJson(o, results));
  printTable(o, results);
}

}  // namespace

void registerHypothesisCommands(CLI::App& sim) {
  auto o = std::make_shared<HypothesesOptions>();
  auto* cmd = sim.add_subcommand("compare-hypotheses",
                                 "Run the paper's study under each learning hypothesis: which of the paper's findings "
                                 "each reproduces, with an A/A check per hypothesis");
  cmd->add_option("--hypotheses", o->hypotheses, "Comma-separated: position-plan, force-plan, guidance-dependent")
      ->capture_default_str();
  cmd->add_option("--subjects", o->subjects, "Subjects per study")->check(CLI::Range(3, 100))->capture_default_str();
  cmd->add_option("--trials", o->trials, "Training and recall trials per mode")
      ->check(CLI::Range(2, 50))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "The study's seed; A/A study k uses seed + k")->capture_default_str();
  cmd->add_option("--aa-seeds", o->aa_seeds, "A/A studies per hypothesis (guidance off in every mode)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  cmd->add_option("--threads", o->threads, "Subjects simulated at once (0: this machine's cores)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  cmd->add_option("--out", o->out_dir, "Folder for the studies")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print JSON: hypotheses [{hypothesis, agrees, differs, p_mode_trajectory, "
                                   "p_mode_force, aa {seeds, significant_trajectory, significant_force, p_mode_trajectory, "
                                   "p_mode_force}, points [{point, source, paper, hattr, agreement}]}]");
  cmd->callback([o] { runHypotheses(*o); });
}

}  // namespace hattr::cli
