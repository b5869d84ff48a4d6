// Studies from Python: open a study database, list its subjects and trials, load a trial's
// samples, run the paper's analysis; create a study from a study file and run its unattended
// (simulated or scripted) subjects, as `hattr study init` and `hattr study run` do.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "hattr/core/error.hpp"
#include "hattr/report/study_analysis.hpp"
#include "hattr/session/study.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/sim/participant.hpp"

namespace hattr::python {
namespace {

using session::StudyDatabase;

py::dict subjectRecord(const session::SubjectRecord& s) {
  std::vector<std::string> order;
  for (const guidance::TrainingMode mode : s.mode_order) order.emplace_back(guidance::modeName(mode));
  return py::dict(py::arg("id") = s.id, py::arg("position") = s.position, py::arg("participant") = s.spec.participant,
                  py::arg("seed") = s.spec.seed, py::arg("mode_order") = order,
                  py::arg("options") = toPython(s.spec.options));
}

py::dict trialRecord(const session::TrialRecord& t) {
  return py::dict(py::arg("trial_id") = t.id, py::arg("subject") = t.plan.subject,
                  py::arg("sequence") = t.plan.sequence, py::arg("mode") = std::string(guidance::modeName(t.plan.mode)),
                  py::arg("phase") = std::string(session::phaseName(t.plan.phase)), py::arg("trial") = t.plan.index,
                  py::arg("status") = std::string(session::trialStatusName(t.status)),
                  py::arg("attempts") = t.attempts, py::arg("interruptions") = t.interruptions,
                  py::arg("started_utc") = t.started_utc, py::arg("ended_utc") = t.ended_utc,
                  py::arg("outcome") = t.outcome, py::arg("sample_count") = t.sample_count,
                  py::arg("disturbed") = t.disturbed, py::arg("disturbed_attempts") = t.disturbed_attempts);
}

/// A study file given as a path or as a dict (the file's JSON; relative expert paths resolve
/// against `base_dir`).
session::StudyDefinition definitionOf(const py::object& study, const std::filesystem::path& base_dir) {
  if (py::isinstance<py::dict>(study)) return session::parseStudy(fromPython(study).dump(), "study dict", base_dir);
  return session::loadStudy(study.cast<std::filesystem::path>());
}

}  // namespace

void bindStudies(py::module_& m) {
  py::class_<StudyDatabase>(m, "Study",
                            "A study database opened read-only: its definition, subjects, trials and recordings. "
                            "Another process may run the study meanwhile.")
      .def_static(
          "open", [](const std::filesystem::path& path) { return StudyDatabase::open(path, session::OpenMode::kReadOnly); },
          py::arg("path"),
          "Opens a study database (a file `hattr study init` or `hattr demo` made) read-only. InputError for a file "
          "that is not a hattr study or comes from a newer hattr.")
      .def_property_readonly("path", &StudyDatabase::file)
      .def_property_readonly("name", [](const StudyDatabase& db) { return db.study().name; })
      .def_property_readonly("skill", [](const StudyDatabase& db) { return db.study().skill; })
      .def_property_readonly("schema_version", &StudyDatabase::schemaVersion)
      .def_property_readonly(
          "definition", [](const StudyDatabase& db) { return toPython(session::studyToJson(db.study())); },
          "The study's definition as stored (the study file's JSON), a dict.")
      .def(
          "subjects",
          [](const StudyDatabase& db) {
            py::list rows;
            for (const session::SubjectRecord& s : db.subjects()) rows.append(subjectRecord(s));
            return rows;
          },
          "Records {id, position, participant, seed, mode_order, options}, in the study's order.")
      .def(
          "trials",
          [](const StudyDatabase& db, const std::optional<std::string>& subject) {
            py::list rows;
            for (const session::TrialRecord& t : db.trials(subject.value_or(""))) rows.append(trialRecord(t));
            return rows;
          },
          py::arg("subject") = py::none(),
          "Records {trial_id, subject, sequence, mode, phase, trial, status, attempts, interruptions, started_utc, "
          "ended_utc, outcome, sample_count, disturbed, disturbed_attempts}: every trial, or one subject's.")
      .def("trial_profile", &StudyDatabase::trialProfile, py::arg("trial_id"),
           "The recording of a completed trial, exactly as stored. InputError for a trial that has none.")
      .def(
          "expert",
          [](const StudyDatabase& db, const std::optional<std::string>& skill) {
            return db.expert(skill.value_or(db.study().skill));
          },
          py::arg("skill") = py::none(), "The expert reference of a skill (default: the study's).")
      .def(
          "analyze",
          [](const StudyDatabase& db, const std::string& normalization, const std::string& cost,
             std::optional<double> band_fraction, unsigned threads) {
            const report::AnalysisOptions options{.normalization = analysis::parseNormalization(normalization),
                                                  .cost = analysis::parseDtwCost(cost),
                                                  .band_fraction = band_fraction.value_or(-1.0),
                                                  .threads = threads};
            nlohmann::json json;
            {
              py::gil_scoped_release unlocked;
              json = report::analysisToJson(report::analyzeStudy(db, options));
            }
            return toPython(json);
          },
          py::kw_only(), py::arg("normalization") = "paper", py::arg("cost") = "abs",
          py::arg("band_fraction") = py::none(), py::arg("threads") = 2,
          "The paper's analysis of the recall trials, as `hattr study analyze --json` prints it (a dict): "
          "recall_costs (records), and per metric ('trajectory', 'force') the ANOVAs, Tukey HSD, per-mode "
          "statistics and each subject's best mode. Nothing is written. Releases the GIL.")
      .def("__enter__", [](StudyDatabase& db) -> StudyDatabase& { return db; }, py::return_value_policy::reference)
      .def("__exit__", [](StudyDatabase&, const py::args&) { return false; });

  m.def(
      "create_study",
      [](const std::filesystem::path& path, const py::object& study, const std::filesystem::path& base_dir) {
        return StudyDatabase::create(path, definitionOf(study, base_dir));
      },
      py::arg("path"), py::arg("study"), py::kw_only(), py::arg("base_dir") = std::filesystem::path("."),
      "Creates a study database at path from a study file (a path) or its JSON as a dict (expert paths relative "
      "to base_dir), as `hattr study init`; returns it open. InputError for an existing file or a bad study.");
  m.def(
      "run_study",
      [](const std::filesystem::path& path, const std::optional<std::string>& subject, std::optional<int> max_trials) {
        py::gil_scoped_release unlocked;
        StudyDatabase db = StudyDatabase::open(path, session::OpenMode::kRunner);
        session::StudyRunner runner(db, sim::makeUnattendedParticipant);
        return runner.run({.only_subject = subject.value_or(""), .max_trials = max_trials.value_or(-1)});
      },
      py::arg("path"), py::kw_only(), py::arg("subject") = py::none(), py::arg("max_trials") = py::none(),
      "Runs a study's unfinished trials of simulated and scripted subjects in simulated time, resuming where it "
      "stopped, as `hattr study run`; returns the number of trials run. People run from the studio; a study with "
      "mentored modes runs from the CLI (it needs the expert's station). Releases the GIL.");
}

}  // namespace hattr::python
