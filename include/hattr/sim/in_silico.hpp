#pragma once
/// The paper's study in silico: synthesize the expert, create a study with the paper's
/// protocol, run it with simulated trainees through the real pipeline (servo loop, paper,
/// guidance, study runner, database), analyze it and write the report. `hattr demo`, the
/// A/A check and the sensitivity sweep are all this one function with other options.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/report/study_analysis.hpp"
#include "hattr/session/study.hpp"
#include "hattr/sim/trainee_model.hpp"

namespace hattr::sim {

struct InSilicoOptions {
  std::filesystem::path out_dir = "demo-out";
  std::string glyph = "na";                 ///< a glyph file, a built-in name or the character (findGlyph)
  int subjects = 10;
  std::uint64_t seed = 1;                   ///< subject i gets seed·1000 + i
  int training_trials = 11;
  int recall_trials = 11;
  bool guidance = true;                     ///< false: an A/A study (no mode ever guides)
  /// The subjects' learning hypothesis, recorded in their options ("hypothesis"); default:
  /// position-plan (data/sim/trainee_model.json). Not together with `model`.
  std::optional<LearningHypothesis> hypothesis;
  std::optional<TraineeModel> model;        ///< a model in place of the hypothesis's file (the sweep)
  bool write_report = true;
  /// Subjects simulated at once (session::RunOptions::subjects_at_once); 0: as many as the
  /// hardware runs at once. The trials and the analysis are the same to the bit for any count.
  int threads = 0;
  /// Progress by stage: "trials" after each trial (done of total), "scoring" as the recall
  /// trials are scored, "report" (0 of 1) before the report is written.
  std::function<void(std::string_view stage, int done, int total)> progress;
};

struct InSilicoResult {
  session::StudyDefinition study;
  std::filesystem::path database;
  std::filesystem::path report_html;        ///< empty without a report
  report::StudyAnalysis analysis;
  std::uint64_t servo_ticks = 0;            ///< simulated servo ticks in all trials
  int trials = 0;
};

/// Simulated subjects S01 .. S<count>, subject i seeded seed·1000 + i, each with `options`.
std::vector<session::SubjectSpec> simulatedSubjects(int count, std::uint64_t seed, const nlohmann::json& options);

/// The paper's study in silico without running it: records the glyph's expert into `dir`
/// (expert.csv, and expert-script.csv which the subjects mean to write) and returns the study
/// (the paper's three modes, o's protocol and subjects). Throws InputError for bad options.
session::StudyDefinition writePaperStudy(const std::filesystem::path& dir, const InSilicoOptions& o);

/// Runs the whole study. An existing study database in out_dir is kept under a new name
/// (study-<time>.sqlite), never overwritten. Throws InputError for bad options or data files.
InSilicoResult runInSilicoStudy(const InSilicoOptions& options);

/// Sets one trainee-model parameter's population value by its file key ("fast_rate", ...);
/// throws InputError for an unknown key or a value outside the parameter's range.
void setModelParameter(TraineeModel& model, std::string_view key, double value);
/// The keys setModelParameter accepts.
std::vector<std::string> modelParameterKeys();

}  // namespace hattr::sim
