// Studies from Python: open a study database, list its subjects and trials, load a trial's
// samples, run the paper's analysis; create a study from a study file and run its unattended
// (simulated or scripted) subjects, as `hattr study init` and `hattr study run` do.

#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "hattr/core/error.hpp"
#include "hattr/ops/study_run.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/report/study_analysis.hpp"
#include "hattr/session/study.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/sim/expert.hpp"

namespace hattr::python {
namespace {

using session::StudyDatabase;

py::dict subjectRecord(const session::SubjectRecord& s) {
  std::vector<std::string> order;
  for (const guidance::TrainingMode mode : s.mode_order) order.emplace_back(guidance::modeName(mode));
  return py::dict(py::arg("id") = s.id, py::arg("position") = s.position, py::arg("participant") = s.spec.participant,
                  py::arg("seed") = s.spec.seed, py::arg("mode_order") = order, py::arg("group") = s.spec.group,
                  py::arg("options") = toPython(s.spec.options));
}

py::dict trialRecord(const session::TrialRecord& t) {
  return py::dict(py::arg("trial_id") = t.id, py::arg("subject") = t.plan.subject,
                  py::arg("sequence") = t.plan.sequence, py::arg("mode") = std::string(guidance::modeName(t.plan.mode)),
                  py::arg("phase") = t.plan.phase, py::arg("trial") = t.plan.index,
                  py::arg("skill") = t.plan.skill, py::arg("group") = t.plan.group,
                  py::arg("session") = t.plan.session + 1, py::arg("day") = t.plan.day,
                  py::arg("block") = t.plan.block + 1,
                  py::arg("status") = std::string(session::trialStatusName(t.status)),
                  py::arg("attempts") = t.attempts, py::arg("interruptions") = t.interruptions,
                  py::arg("started_utc") = t.started_utc, py::arg("ended_utc") = t.ended_utc,
                  py::arg("outcome") = t.outcome, py::arg("sample_count") = t.sample_count,
                  py::arg("disturbed") = t.disturbed, py::arg("disturbed_attempts") = t.disturbed_attempts);
}

/// A study file given as a path or as a dict (the file's JSON; relative expert paths resolve
/// against `base_dir`).
using StudySource = std::variant<py::dict, std::filesystem::path>;
session::StudyDefinition definitionOf(const StudySource& study, const std::filesystem::path& base_dir) {
  if (const auto* json = std::get_if<py::dict>(&study)) {
    return session::parseStudy(fromPython(*json).dump(), "study dict", base_dir);
  }
  return session::loadStudy(std::get<std::filesystem::path>(study));
}

/// A study database open read-only until closed (close(), or the end of a `with` block).
class OpenStudy {
 public:
  explicit OpenStudy(const std::filesystem::path& path)
      : db_(StudyDatabase::open(path, session::OpenMode::kReadOnly)) {}
  /// The database; InputError once closed.
  [[nodiscard]] const StudyDatabase& db() const {
    HATTR_THROW_UNLESS(db_.has_value(), "the study is closed");
    return *db_;
  }
  void close() { db_.reset(); }

 private:
  std::optional<StudyDatabase> db_;
};

/// Study: opening one, its definition, subjects, trials and recordings.
void bindStudyRecords(py::class_<OpenStudy>& study) {
  study
      .def_static(
          "open", [](const std::filesystem::path& path) { return OpenStudy(path); }, py::arg("path"),
          "Opens a study database (a file `hattr study init` or `hattr demo` made) read-only. InputError for a file "
          "that is not a hattr study or comes from a newer hattr.")
      .def_property_readonly("path", [](const OpenStudy& s) { return s.db().file(); })
      .def_property_readonly("name", [](const OpenStudy& s) { return s.db().study().name; })
      .def_property_readonly("skill", [](const OpenStudy& s) { return s.db().study().skill; })
      .def_property_readonly("schema_version", [](const OpenStudy& s) { return s.db().schemaVersion(); })
      .def_property_readonly(
          "definition", [](const OpenStudy& s) { return toPython(session::studyToJson(s.db().study())); },
          "The study's definition as stored (the study file's JSON), a dict.")
      .def(
          "subjects",
          [](const OpenStudy& s) {
            py::list rows;
            for (const session::SubjectRecord& subject : s.db().subjects()) rows.append(subjectRecord(subject));
            return rows;
          },
          "Records {id, position, participant, seed, mode_order, options}, in the study's order.")
      .def(
          "trials",
          [](const OpenStudy& s, const std::optional<std::string>& subject) {
            py::list rows;
            for (const session::TrialRecord& t : s.db().trials(subject.value_or(""))) rows.append(trialRecord(t));
            return rows;
          },
          py::arg("subject") = py::none(),
          "Records {trial_id, subject, sequence, mode, phase, trial, status, attempts, interruptions, started_utc, "
          "ended_utc, outcome, sample_count, disturbed, disturbed_attempts}: every trial, or one subject's.")
      .def(
          "trial_profile", [](const OpenStudy& s, std::int64_t trial_id) { return s.db().trialProfile(trial_id); },
          py::arg("trial_id"), "The recording of a completed trial, exactly as stored. InputError for a trial that has none.")
      .def(
          "expert",
          [](const OpenStudy& s, const std::optional<std::string>& skill) {
            return s.db().expert(skill.value_or(s.db().study().skill));
          },
          py::arg("skill") = py::none(), "The expert reference of a skill (default: the study's).");
}

/// Study: the paper's analysis (or the design's), closing, `with` blocks.
void bindStudyAnalysis(py::class_<OpenStudy>& study) {
  study
      .def(
          "analyze",
          [](const OpenStudy& s, const std::string& normalization, const std::string& cost,
             std::optional<double> band_fraction, unsigned threads) {
            const report::AnalysisOptions options{.normalization = analysis::parseNormalization(normalization),
                                                  .cost = analysis::parseDtwCost(cost),
                                                  .band_fraction = band_fraction.value_or(-1.0),
                                                  .threads = threads};
            const StudyDatabase& db = s.db();
            nlohmann::json json;
            {
              py::gil_scoped_release unlocked;
              // As `hattr study analyze` chooses: the paper's analysis for its design, else the design's.
              json = report::chooseAnalysis(db).balanced ? report::analysisToJson(report::analyzeStudy(db, options))
                                                        : report::designAnalysisToJson(report::analyzeDesign(db, options));
            }
            return toPython(json);
          },
          py::kw_only(), py::arg("normalization") = "paper", py::arg("cost") = "abs",
          py::arg("band_fraction") = py::none(), py::arg("threads") = 2,
          "The study's analysis, as `hattr study analyze --json` prints it (a dict). The paper's design: "
          "recall_costs (records), and per metric ('trajectory', 'force') the ANOVAs, Tukey HSD, per-mode "
          "statistics and each subject's best mode. Any other design: trial_scores (records), trials_left_out, curves, "
          "phase_cells, retention, transfer and conclusions (docs/analysis.md, 'Designs'). Nothing is "
          "written. Releases the GIL.")
      .def("close", &OpenStudy::close, "Closes the database; the study can no longer be read through this object.")
      .def("__enter__", [](OpenStudy& s) -> OpenStudy& { return s; }, py::return_value_policy::reference)
      .def("__exit__", [](OpenStudy& s, const py::args&) {
        s.close();
        return false;
      });
}

/// The class hattr.Study.
void bindStudyClass(py::module_& m) {
  py::class_<OpenStudy> study(m, "Study",
                              "A study database opened read-only: its definition, subjects, trials and recordings. "
                              "Another process may run the study meanwhile. close() (or a `with` block) closes it.");
  bindStudyRecords(study);
  bindStudyAnalysis(study);
}

/// Creating a study and running its unattended subjects.
void bindStudyFunctions(py::module_& m) {
  m.def(
      "create_study",
      [](const std::filesystem::path& path, const StudySource& study, const std::filesystem::path& base_dir) {
        {
          session::StudyDefinition definition = definitionOf(study, base_dir);
          sim::recordNamedExperts(definition);                 // experts named by their glyph ("na", "ந")
          (void)session::checkExpertsRenderable(definition);  // an expert the device cannot render: refused
          (void)StudyDatabase::create(path, definition);
        }
        return OpenStudy(path);
      },
      py::arg("path"), py::arg("study"), py::kw_only(), py::arg("base_dir") = std::filesystem::path("."),
      "Creates a study database at path from a study file (a path) or its JSON as a dict (expert paths relative "
      "to base_dir; an expert may be named by its glyph, 'na' or 'ந', and is then recorded), as `hattr study "
      "init`; returns it opened read-only. InputError for an existing file or a bad study.");
  m.def(
      "run_study",
      [](const std::filesystem::path& path, const std::optional<std::string>& subject, std::optional<int> max_trials) {
        py::gil_scoped_release unlocked;
        return ops::runStudy({.db = path, .subject = subject.value_or(""), .max_trials = max_trials.value_or(-1)})
            .trials_run;
      },
      py::arg("path"), py::kw_only(), py::arg("subject") = py::none(), py::arg("max_trials") = py::none(),
      "Runs a study's unfinished trials of simulated and scripted subjects in simulated time, resuming where it "
      "stopped, as `hattr study run` (mentored modes too: the study file's mentor block is the expert's station); "
      "returns the number of trials run. People run from the studio. Releases the GIL.");
}

}  // namespace

void bindStudies(py::module_& m) {
  bindStudyClass(m);
  bindStudyFunctions(m);
}

}  // namespace hattr::python
