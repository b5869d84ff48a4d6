// Simulation from Python: one trial on the simulated pen (a hand script, a mode, simulated
// time), as `hattr record` and `hattr train` run it, and the paper's whole study in silico,
// as `hattr demo` runs it.

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "hattr/core/error.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/ops/power_run.hpp"
#include "hattr/ops/trial_run.hpp"
#include "hattr/report/study_analysis.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/sim/in_silico.hpp"

namespace hattr::python {
namespace {

/// A profile given as a HapticProfile or a file; `label` becomes the file's name when it is one.
using ProfileSource = std::variant<HapticProfile, std::filesystem::path>;
HapticProfile profileOf(const ProfileSource& given, std::string& label) {
  if (const auto* profile = std::get_if<HapticProfile>(&given)) return *profile;
  const auto& path = std::get<std::filesystem::path>(given);
  label = path.string();
  return io::readProfileCsv(path);
}

/// A world configuration: the defaults (None), a dict of the world file's JSON, or a file.
using WorldSource = std::optional<std::variant<py::dict, std::filesystem::path>>;
render::WorldConfig worldOf(const WorldSource& world) {
  if (!world) return {};
  if (const auto* json = std::get_if<py::dict>(&*world)) {
    return render::parseWorldConfig(fromPython(*json).dump(), "world dict");
  }
  return render::loadWorldConfig(std::get<std::filesystem::path>(*world));
}

py::dict trialRecord(session::TrialResult result) {
  const std::string disturbed = session::disturbanceOf(result);
  return py::dict(py::arg("profile") = std::move(result.profile), py::arg("clamps") = result.clamps,
                  py::arg("ticks") = result.ticks, py::arg("missed_samples") = result.missed_samples,
                  py::arg("overruns") = result.overruns, py::arg("faults") = result.faults,
                  py::arg("link_faults") = result.link_faults, py::arg("stalls") = result.stalls,
                  py::arg("clock") = result.clock, py::arg("end_reason") = result.end_reason,
                  py::arg("failure") = result.failure, py::arg("disturbed") = disturbed);
}

/// run_trial: one trial on the simulated pen, as `hattr record` and `hattr train` run it.
void bindRunTrial(py::module_& m) {
  m.def(
      "run_trial",
      [](const ProfileSource& hand, const std::optional<ProfileSource>& reference, const std::string& mode,
         const WorldSource& world, const std::string& device, double rate_hz, const std::string& clock,
         double tail_s, double pen_up_end_s, double max_duration_s, const std::string& indexing, double speed,
         const std::string& subject, const std::string& skill, int trial, const std::map<std::string, std::variant<double, std::string>>& params,
         std::uint64_t seed) {
        session::ScriptedTrialOptions options{.rate_hz = rate_hz, .tail_s = tail_s, .pen_up_end_s = pen_up_end_s,
                                              .max_duration_s = max_duration_s, .clock = session::parseClock(clock),
                                              .subject = subject, .skill = skill, .mode = guidance::parseMode(mode),
                                              .indexing = guidance::parseIndexing(indexing), .speed = speed,
                                              .trial = trial, .seed = seed};
        // A number as its shortest exact text; a choice by its name.
        for (const auto& [name, value] : params) {
          options.parameters.emplace_back(name, std::holds_alternative<double>(value)
                                                    ? fmt::format("{}", std::get<double>(value))
                                                    : std::get<std::string>(value));
        }
        ops::ScriptedTrialRun run;
        run.device = device;
        run.hand = profileOf(hand, options.hand_label);
        if (reference) run.reference = profileOf(*reference, options.reference_label);
        run.world = worldOf(world);
        run.options = std::move(options);
        session::TrialResult result;
        {
          // As `hattr train`: a reference or a hand the device cannot render is refused first.
          py::gil_scoped_release unlocked;
          result = ops::runScriptedTrial(std::move(run)).trial;
        }
        return trialRecord(std::move(result));
      },
      py::arg("hand"), py::arg("reference") = py::none(), py::arg("mode") = "basic", py::kw_only(),
      py::arg("world") = py::none(), py::arg("device") = "sim://pen", py::arg("rate_hz") = 1000.0,
      py::arg("clock") = "sim", py::arg("tail_s") = 0.3, py::arg("pen_up_end_s") = 0.0,
      py::arg("max_duration_s") = 0.0, py::arg("indexing") = "time", py::arg("speed") = 1.0,
      py::arg("subject") = "", py::arg("skill") = "", py::arg("trial") = 0,
      py::arg("params") = std::map<std::string, std::variant<double, std::string>>{}, py::arg("seed") = 1,
      "One trial as `hattr train` (with a reference) or `hattr record` (without) runs it: the simulated hand "
      "writes `hand` (a HapticProfile or a profile file) on the paper, with the strategy's guidance toward "
      "`reference` (mode: a name of hattr.strategies(), not a mentored one; params: its parameters by name in "
      "the units hattr.strategies() gives, or a choice's name; seed: the noise's; a scheduled strategy plays its "
      "first trial's law and gain). Simulated time "
      "unless clock='real'. The trial lasts the "
      "script plus tail_s [s], or with pen_up_end_s > 0 [s] ends once the pen has been up that long. world: "
      "None (defaults), a dict or a world file. Returns {profile, clamps, ticks, missed_samples, overruns, "
      "faults, link_faults, stalls, clock, end_reason, failure, disturbed}; disturbed says how the trial was "
      "disturbed (stalls, missed samples, the pen through the paper, the device at its force limit, ...), \"\" when clean. "
      "With a reference, a reference or hand the device cannot render (too strong, outside its workspace) raises "
      "InputError with the numbers and the remedy. Releases the GIL.");
}

/// strategies: the training strategies and their parameters.
void bindStrategies(py::module_& m) {
  m.def(
      "strategies", [] { return toPython(ops::strategiesJson()); },
      "The training strategies, as `hattr strategies --json` lists them: [{name, plain_name, description, source, "
      "mentored, scheduled, parameters [{name, unit, default, min, max, meaning} or {name, default, choices, "
      "meaning}]}].");
}

/// simulate_study: the paper's study in silico, as `hattr demo` runs it.
void bindSimulateStudy(py::module_& m) {
  m.def(
      "simulate_study",
      [](const std::filesystem::path& out_dir, int subjects, std::uint64_t seed, int training_trials,
         int recall_trials, bool guidance, const std::string& glyph, bool write_report) {
        const sim::InSilicoOptions options{.out_dir = out_dir, .glyph = glyph, .subjects = subjects, .seed = seed,
                                           .training_trials = training_trials, .recall_trials = recall_trials,
                                           .guidance = guidance, .write_report = write_report};
        sim::InSilicoResult result;
        nlohmann::json analysis;
        {
          py::gil_scoped_release unlocked;
          result = sim::runInSilicoStudy(options);
          analysis = report::analysisToJson(result.analysis);
        }
        return py::dict(py::arg("database") = result.database,
                        py::arg("report_html") = result.report_html.empty() ? py::none() : py::cast(result.report_html),
                        py::arg("trials") = result.trials, py::arg("servo_ticks") = result.servo_ticks,
                        py::arg("analysis") = toPython(analysis));
      },
      py::arg("out_dir"), py::kw_only(), py::arg("subjects") = 10, py::arg("seed") = 1,
      py::arg("training_trials") = 11, py::arg("recall_trials") = 11, py::arg("guidance") = true,
      py::arg("glyph") = "na", py::arg("write_report") = true,
      "The paper's study in silico, as `hattr demo`: the simulated expert, a study with the paper's protocol, "
      "simulated trainees through the real pipeline, the analysis and (write_report) the report, all in out_dir "
      "(an existing study there is kept under a new name). guidance=False is the A/A check. Returns {database, "
      "report_html, trials, servo_ticks, analysis}. Releases the GIL.");
}

/// hattr.power_analysis: `hattr sim power` in this process (ops::runPowerAnalysis).
void bindPowerAnalysis(py::module_& m) {
  m.def(
      "power_analysis",
      [](const std::optional<std::filesystem::path>& study, const std::optional<std::string>& glyph,
         const std::optional<int> trials, const std::vector<int>& subjects, int replicates, std::uint64_t seed,
         double alpha, int threads, const std::string& phase, const std::string& hypothesis) {
        // As `hattr sim power`: glyph and trials are the paper's study's; a study file has its own.
        HATTR_THROW_UNLESS(!study || (!glyph && !trials),
                           "power_analysis: glyph and trials are the paper's study's; the study file {} has its own",
                           study ? study->string() : "");
        HATTR_THROW_UNLESS(!trials || (*trials >= 2 && *trials <= 50),
                           "power_analysis: trials: expected 2 to 50 training and recall trials per mode, got {}",
                           trials.value_or(0));
        const sim::PowerOptions options{.study = study.value_or(std::filesystem::path()), .glyph = glyph.value_or("na"),
                                        .training_trials = trials.value_or(11), .recall_trials = trials.value_or(11),
                                        .subject_counts = subjects,
                                        .replicates = replicates, .seed = seed, .alpha = alpha, .threads = threads,
                                        .phase = phase, .hypothesis = hypothesis};
        nlohmann::json json;
        {
          py::gil_scoped_release unlocked;
          json = ops::runPowerAnalysis(options).toJson();
        }
        return toPython(json);
      },
      py::arg("study") = py::none(), py::kw_only(), py::arg("glyph") = py::none(), py::arg("trials") = py::none(),
      py::arg("subjects") = std::vector<int>{6, 10, 20, 40}, py::arg("replicates") = 200, py::arg("seed") = 1,
      py::arg("alpha") = 0.05, py::arg("threads") = 2, py::arg("phase") = "", py::arg("hypothesis") = "",
      "A power analysis as `hattr sim power --json` prints it (one process): `replicates` simulated studies "
      "of each number of subjects in `subjects`, each analyzed as its design says, and the share that finds "
      "the difference at `alpha`. study: a study file whose subjects are simulated (None: the paper's study "
      "in silico, with `glyph` (default 'na') and `trials` training and recall trials per mode, 2 to 50, default "
      "11); phase: a design's phase to compare; hypothesis: a learning hypothesis for every subject; threads: "
      "subjects simulated at once. Releases the GIL.");
}

}  // namespace

void bindSimulation(py::module_& m) {
  bindRunTrial(m);
  bindStrategies(m);
  bindSimulateStudy(m);
  bindPowerAnalysis(m);
}

}  // namespace hattr::python
