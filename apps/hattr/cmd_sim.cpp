// hattr sim expert | aa | sweep: the simulated expert, and the checks that keep the trainee
// model honest.

#include <functional>
#include <iostream>
#include <sstream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"
#include "hattr/sim/in_silico.hpp"

namespace hattr::cli {
namespace {

struct SimOptions {
  std::string glyph = "na";
  std::string output;
  std::string script_output;
  bool force = false;
  int seeds = 20;
  int subjects = 10;
  int trials = 5;
  std::string out_dir = "sim-out";
  std::string parameter;
  std::string values;
  std::string hypothesis = "position-plan";
  bool json = false;
};

const analysis::AnovaRow* row(const analysis::AnovaTable& t, const std::string& source) {
  for (const auto& r : t.rows) {
    if (r.source == source) return &r;
  }
  return nullptr;
}

void runExpert(const SimOptions& opt) {
  std::vector<std::filesystem::path> outputs{opt.output};
  if (!opt.script_output.empty()) outputs.emplace_back(opt.script_output);
  checkOutputFiles(outputs, opt.force);  // both checked before either is written
  const sim::Glyph glyph = sim::findGlyph(opt.glyph);
  const HapticProfile script = sim::expertScript(glyph);
  session::TrialEnvironment env("sim://pen", render::WorldConfig{}, 1000.0);
  const HapticProfile expert = sim::recordExpert(env, script, {.subject = "expert", .skill = glyph.name, .source = "sim:expert"});
  const auto overwrite = opt.force ? hattr::Overwrite::kReplace : hattr::Overwrite::kRefuse;
  io::writeProfileCsv(expert, opt.output, overwrite);
  if (!opt.script_output.empty()) io::writeProfileCsv(script, opt.script_output, overwrite);
  std::cout << fmt::format("expert '{}' -> {}: {} samples, {:.2f} s{}\n", glyph.name, opt.output, expert.size(),
                           expert.duration_s(), opt.script_output.empty() ? "" : fmt::format(" (script: {})", opt.script_output));
}

/// The built-in glyphs, one a line, name first: the character, its strokes and its size.
void runGlyphs(const SimOptions& opt) {
  nlohmann::json rows = nlohmann::json::array();
  for (const sim::Glyph& glyph : sim::builtInGlyphs()) {
    const sim::GlyphBounds box = sim::glyphBounds(glyph);
    const Eigen::Vector2d size_mm = (box.max - box.min) * units::kMillimetresPerMetre;
    rows.push_back({{"name", glyph.name}, {"character", glyph.character}, {"unicode", glyph.unicode},
                    {"strokes", glyph.strokes.size()}, {"width_mm", size_mm.x()}, {"height_mm", size_mm.y()},
                    {"path_mm", units::metresToMillimetres(sim::glyphPathLength(glyph))}});
  }
  if (opt.json) return printJson({{"glyphs", rows}});
  std::cout << fmt::format("{:<12} {:<9} {:<8} {:>7} {:>14} {:>9}\n", "name", "character", "unicode", "strokes",
                           "size (w×h mm)", "path mm");
  for (const auto& r : rows) {
    std::cout << fmt::format("{:<12} {:<9} {:<8} {:>7} {:>7.1f}×{:<6.1f} {:>9.1f}\n", r["name"].get<std::string>(),
                             r["character"].get<std::string>(), r["unicode"].get<std::string>(),
                             r["strokes"].get<std::size_t>(), r["width_mm"].get<double>(), r["height_mm"].get<double>(),
                             r["path_mm"].get<double>());
  }
}

/// Moves `progress` through one study of several (`before` studies done): its trials.
std::function<void(std::string_view, int, int)> withinStudy(Progress& progress, double before) {
  return [&progress, before](std::string_view stage, int done, int total) {
    if (stage == "trials" && total > 0) progress.update(before + static_cast<double>(done) / total);
  };
}

/// One reduced study per seed with guidance switched off in every mode.
void runAa(const SimOptions& opt) {
  const sim::LearningHypothesis hypothesis = sim::parseHypothesis(opt.hypothesis, "--hypothesis");
  nlohmann::json seeds = nlohmann::json::array();
  int significant[2] = {0, 0};
  // The studies' folders name the glyph and the hypothesis: runs of others into the same --out
  // keep their own (aa-loop-position-plan-001).
  std::string skill = sim::findGlyph(opt.glyph).name;
  Progress progress("A/A", opt.seeds, "studies");
  for (int s = 1; s <= opt.seeds; ++s) {
    progress.update(s - 1, fmt::format("A/A: study {} of {}", s, opt.seeds));
    const auto r = sim::runInSilicoStudy({.out_dir = fmt::format("{}/aa-{}-{}-{:03}", opt.out_dir, skill, sim::hypothesisName(hypothesis), s),
                                          .glyph = opt.glyph,
                                          .subjects = opt.subjects,
                                          .seed = static_cast<std::uint64_t>(s), .training_trials = opt.trials,
                                          .recall_trials = opt.trials, .guidance = false,
                                          .hypothesis = hypothesis,
                                          .write_report = false,
                                          .progress = withinStudy(progress, s - 1)});
    skill = r.study.skill;
    const double p_traj = row(r.analysis.trajectory.overall, "mode")->p;
    const double p_force = row(r.analysis.force.overall, "mode")->p;
    significant[0] += p_traj < 0.05 ? 1 : 0;
    significant[1] += p_force < 0.05 ? 1 : 0;
    seeds.push_back({{"seed", s}, {"p_mode_trajectory", p_traj}, {"p_mode_force", p_force}});
  }
  progress.finish();
  const nlohmann::json json = {{"glyph", skill}, {"hypothesis", opt.hypothesis}, {"seeds", seeds}, {"alpha", 0.05},
                               {"fraction_significant_trajectory", static_cast<double>(significant[0]) / opt.seeds},
                               {"fraction_significant_force", static_cast<double>(significant[1]) / opt.seeds}};
  if (opt.json) return printJson(json);
  std::cout << fmt::format("A/A check ({} seeds, {} subjects, {}+{} trials per mode, glyph {}, guidance off in every "
                           "mode, {} learner):\n"
                           "  mode effect significant at α = 0.05: trajectory {}/{}, force {}/{} (expected about {:.1f})\n",
                           opt.seeds, opt.subjects, opt.trials, opt.trials, skill, opt.hypothesis, significant[0], opt.seeds,
                           significant[1], opt.seeds, 0.05 * opt.seeds);
}

/// A reduced study per value of one learning-rule parameter; where the conclusions change.
void runSweep(const SimOptions& opt) {
  const sim::TraineeModel base = sim::loadTraineeModel(sim::defaultDataDir() / "sim" / "trainee_model.json");
  std::vector<double> values;
  std::stringstream in(opt.values);
  for (std::string v; std::getline(in, v, ',');) {
    try {
      values.push_back(std::stod(v));
    } catch (const std::exception&) {
      throw InputError(fmt::format("--values: expected comma-separated numbers, got \"{}\"", v));
    }
  }
  HATTR_THROW_UNLESS(!values.empty(), "--values: expected at least one number");
  nlohmann::json rows = nlohmann::json::array();
  std::string baseline;
  // The studies' folders name the glyph (sweep-loop-slow_rate-0.01).
  std::string skill = sim::findGlyph(opt.glyph).name;
  Progress progress("sweep", static_cast<double>(values.size()), "studies");
  for (const double v : values) {
    progress.update(static_cast<double>(rows.size()), fmt::format("sweep: {} = {}", opt.parameter, v));
    sim::TraineeModel model = base;
    sim::setModelParameter(model, opt.parameter, v);
    const auto r = sim::runInSilicoStudy({.out_dir = fmt::format("{}/sweep-{}-{}-{}", opt.out_dir, skill, opt.parameter, v),
                                          .glyph = opt.glyph, .subjects = opt.subjects, .training_trials = opt.trials,
                                          .recall_trials = opt.trials, .model = model, .write_report = false,
                                          .progress = withinStudy(progress, static_cast<double>(rows.size()))});
    skill = r.study.skill;
    nlohmann::json entry = {{"value", v}};
    std::string conclusion;
    for (const auto* m : {&r.analysis.trajectory, &r.analysis.force}) {
      const auto best = std::min_element(m->per_mode_stats.begin(), m->per_mode_stats.end(),
                                         [](const auto& a, const auto& b) { return a.stats.mean < b.stats.mean; });
      const double p = row(m->overall, "mode")->p;
      entry[m->metric] = {{"best_mode", best->a_level}, {"p_mode", p}};
      conclusion += fmt::format("{}:{}{} ", m->metric, best->a_level, p < 0.05 ? "*" : "");
    }
    if (baseline.empty()) baseline = conclusion;
    entry["conclusion"] = conclusion;
    entry["same_as_first"] = conclusion == baseline;
    rows.push_back(entry);
    progress.finish();
    if (!opt.json) {
      std::cout << fmt::format("{} = {:<8} best mode (* = mode effect p < 0.05): {}{}\n", opt.parameter, v, conclusion,
                               conclusion == baseline ? "" : "  <- differs");
    }
  }
  if (opt.json) printJson({{"parameter", opt.parameter}, {"glyph", skill}, {"rows", rows}});
}

}  // namespace

void registerSimCommands(CLI::App& app) {
  auto* simc = app.add_subcommand("sim", "The simulated expert and the checks of the simulated-trainee model");
  simc->require_subcommand(1);
  auto opt = std::make_shared<SimOptions>();

  auto* expert = simc->add_subcommand("expert", "Synthesize the expert writing a glyph and record their haptic profile");
  constexpr const char* kGlyphHelp = "The glyph: a glyph file, a built-in name (na, loop, small-a, ...: hattr sim glyphs) or the character (ந, a, A, 7)";
  expert->add_option("--glyph", opt->glyph, kGlyphHelp)->capture_default_str();
  expert->add_option("-o,--output", opt->output, "The expert's haptic profile")->required();
  expert->add_option("--script-out", opt->script_output, "Also write the script the expert meant to write");
  expert->add_flag("--force", opt->force, "Replace existing files");
  expert->callback([opt] { runExpert(*opt); });

  auto* glyphs = simc->add_subcommand("glyphs", "List the built-in glyphs (data/glyphs): name, character, strokes, size");
  glyphs->add_flag("--json", opt->json, "Print JSON: glyphs [{name, character, unicode, strokes, width_mm, height_mm, path_mm}]");
  glyphs->callback([opt] { runGlyphs(*opt); });

  auto* aa = simc->add_subcommand("aa", "A/A check: guidance off in every mode; how often is the mode effect significant?");
  aa->add_option("--seeds", opt->seeds, "Studies to run")->check(CLI::Range(1, 1000))->capture_default_str();
  aa->add_option("--subjects", opt->subjects, "Subjects per study")->check(CLI::Range(2, 100))->capture_default_str();
  aa->add_option("--trials", opt->trials, "Training and recall trials per mode")->check(CLI::Range(2, 50))->capture_default_str();
  aa->add_option("--glyph", opt->glyph, kGlyphHelp)->capture_default_str();
  aa->add_option("--out", opt->out_dir, "Folder for the studies")->capture_default_str();
  aa->add_option("--hypothesis", opt->hypothesis, "Learning hypothesis: position-plan, force-plan, guidance-dependent")
      ->capture_default_str();
  aa->add_flag("--json", opt->json, "Print JSON: glyph, hypothesis, seeds [{seed, p_mode_trajectory, p_mode_force}], fractions");
  aa->callback([opt] { runAa(*opt); });

  auto* sweep = simc->add_subcommand("sweep", "Sensitivity: rerun the study over values of one learning-rule parameter");
  sweep->add_option("--param", opt->parameter, "Trainee-model parameter (fast_rate, slow_rate, slow_retention, ...)")->required();
  sweep->add_option("--values", opt->values, "Comma-separated values")->required();
  sweep->add_option("--subjects", opt->subjects, "Subjects per study")->check(CLI::Range(2, 100))->capture_default_str();
  sweep->add_option("--trials", opt->trials, "Training and recall trials per mode")->check(CLI::Range(2, 50))->capture_default_str();
  sweep->add_option("--glyph", opt->glyph, kGlyphHelp)->capture_default_str();
  sweep->add_option("--out", opt->out_dir, "Folder for the studies")->capture_default_str();
  sweep->add_flag("--json", opt->json, "Print JSON: parameter, glyph, rows [{value, best mode and p per metric, same_as_first}]");
  sweep->callback([opt] { runSweep(*opt); });

  registerPowerCommands(*simc);
  registerPlanCommand(*simc);
  registerHypothesisCommands(*simc);
  registerStrategyComparisonCommand(*simc);
}

}  // namespace hattr::cli
