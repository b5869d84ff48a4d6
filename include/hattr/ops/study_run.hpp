#pragma once
/// Running a study's unattended subjects (`hattr study run`, Python's `run_study`) as one
/// library call: the study database opened as its runner, each subject's participant (a
/// simulated trainee or a hand script), the expert's station when the study has mentored modes
/// (the study file's mentor block), and the runner, resuming where the study stopped.
///
/// Threads: blocks until the run ends; with subjects_at_once > 1 the runner runs subjects on
/// threads of its own (session::RunOptions). The callbacks run one at a time.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/session/study_runner.hpp"

namespace hattr::ops {

struct StudyRunOptions {
  std::filesystem::path db;            ///< a study database: a file or a postgresql:// address
  std::string subject;                 ///< only this subject; "" = all
  session::Clock clock = session::Clock::kSimulated;
  int max_trials = -1;                 ///< stop after this many trials (-1: all)
  int subjects_at_once = 1;            ///< session::RunOptions::subjects_at_once
  double lease_timeout_s = 30.0;       ///< a PostgreSQL study's subject leases
  /// Sessions on later days wait for their date (session::RunOptions::follow_calendar); false:
  /// the days are simulated and every session follows at once.
  bool follow_calendar = false;
  /// Before the first trial: how many this run has to do (the unfinished trials of the
  /// subjects it runs, at most max_trials).
  std::function<void(int trials_to_run)> started;
  /// After each trial.
  std::function<void(const session::RunProgress&)> progress;
};

struct StudyRunResult {
  int trials_to_run = 0;               ///< what the run had to do when it began
  int trials_run = 0;                  ///< what it did
  std::vector<session::WaitingSubject> waiting;  ///< left until their next session is due
  /// {trials_to_run, trials_run, waiting: [{subject, schedule}]}.
  [[nodiscard]] nlohmann::json toJson() const;
};

/// A subject's place in the schedule as JSON: {timing, session, sessions, day, due, days_off,
/// text} (session from 1; due null when there is none).
nlohmann::json scheduleJson(const session::SubjectSchedule& schedule);

/// Runs the study. Throws InputError for a database that is no study or a subject it does not
/// have, hattr::Error when another runner holds the study (SQLite) or a trial cannot be stored.
StudyRunResult runStudy(const StudyRunOptions& options);

}  // namespace hattr::ops
