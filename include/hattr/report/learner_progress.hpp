#pragma once
/// One learner's progress through a practice plan (ops/practice_plan.hpp) or any study, for a
/// teacher, a therapist or a parent: every completed trial with its scores and the kinematics
/// that matter when a child writes (time, pen lifts, speed changes), each session summed up in
/// one plain sentence, the best and the latest trial of each letter marked, and a printable page.
///
/// "Written alone" trials (guidance off: baseline, post-test, retention, transfer) measure what
/// the learner can do; guided trials are shown but neither compared nor marked best, for the
/// guidance did part of the work. A session's shape is the mean shape cost of its trials written
/// alone; "the start" is the first session's (its baseline when it has one). Costs are the
/// paper's DTW (analysis/trial_score.hpp): lower is closer to the model letter. hattr's reading:
/// within ±5 % of the start is "about the same"; docs/studio.md, "For teachers".
///
/// Offline code: any thread but the servo thread.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/session/learner.hpp"
#include "hattr/session/study_database.hpp"

namespace hattr::report {

struct ProgressTrial {
  std::int64_t trial_id = 0;
  int number = 1;            ///< the learner's trial number over the plan, from 1
  int session = 1;           ///< from 1
  std::string date;          ///< the local date it was written ("2026-11-29")
  std::string phase;
  std::string skill;         ///< the letter as written (session::letterName)
  int trial = 1;             ///< within its block, from 1
  bool guided = false;
  double shape = 0.0;        ///< DTW x + y (lower: closer to the model)
  double force = 0.0;        ///< DTW fx + fy + fz
  double writing_time_s = 0.0;
  double pen_lifts = 0.0;
  double velocity_peaks = 0.0;  ///< speed changes: fewer is smoother
  bool best = false;         ///< the lowest shape cost of its letter's trials written alone
  bool latest = false;       ///< its letter's last trial written alone
};

struct ProgressSession {
  int session = 1;           ///< from 1
  int day = 0;               ///< the plan's day offset
  std::string date;          ///< when it was written (its first trial's local date); "" before
  int planned = 0;
  int completed = 0;
  int guided = 0;            ///< completed guided trials
  int alone = 0;             ///< completed trials written alone
  double alone_shape = 0.0;  ///< mean shape cost of the trials written alone (NaN: none)
  double change = 0.0;       ///< the shape's change from the start, by letter (+0.2: 20 % closer; NaN)
  bool best_so_far = false;  ///< the lowest alone_shape up to this session
  double writing_time_s = 0.0;  ///< means over its completed trials (NaN: none)
  double pen_lifts = 0.0;
  double velocity_peaks = 0.0;
  std::string sentence;      ///< the session in one plain sentence
};

struct LearnerProgress {
  std::string study;         ///< the plan's name
  std::filesystem::path file;
  session::Learner learner;
  std::vector<std::string> letters;
  std::string strategy;       ///< the plain name ("Guided path")
  std::string strategy_name;  ///< the technical one ("PCONTROL")
  std::string next;           ///< the schedule's next step ("next session 2 of 6 (day 2): due today")
  std::vector<ProgressSession> sessions;
  std::vector<ProgressTrial> trials;  ///< completed ones, in the order written
};

/// The progress of `subject` (the only person when empty). Throws InputError for an unknown
/// subject, or an empty subject in a study of several.
[[nodiscard]] LearnerProgress learnerProgress(const session::StudyDatabase& db, const std::string& subject = "");

[[nodiscard]] nlohmann::json toJson(const LearnerProgress& progress);

struct ProgressPageOptions {
  bool identified = true;  ///< print the learner's name and notes (false: the code only)
  std::string printed;     ///< the date printed on the page ("" none)
  /// The whole page. False: the sessions' sentences and a narrow table of the trials only, for
  /// a view that shows the learner, the next session and the curve itself (the Learners tab).
  bool whole_page = true;
};

/// The printable page: one self-contained HTML file (the curve inline SVG, print CSS, no script).
[[nodiscard]] std::string progressPageHtml(const LearnerProgress& progress, const ProgressPageOptions& options = {});

}  // namespace hattr::report
