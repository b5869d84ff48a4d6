#pragma once
/// One learner's progress through a practice plan (ops/practice_plan.hpp) or any study, for a
/// teacher, a therapist or a parent: every completed trial with its scores and the kinematics
/// that matter when a child writes (time, pen lifts, speed changes), each session summed up in
/// one plain sentence, the best and the latest trial of each letter marked, and a printable page.
///
/// "Written alone" trials (guidance off: baseline, post-test, retention, transfer) measure what
/// the learner can do; guided trials are shown but neither compared nor marked best, for the
/// guidance did part of the work (a plan whose every trial is guided compares those). Disturbed
/// trials are shown, not compared. The start: each letter's baseline in the first session with
/// compared trials, else that session's trials (then that session is the start itself). A
/// session's shape per letter: the mean of its compared trials after the baseline; its change:
/// (start − now) / start, averaged over the letters. Costs are the paper's DTW
/// (analysis/trial_score.hpp): lower is closer to the model letter. hattr's reading: within ±5 %
/// of the start is "about the same"; "the best so far" is a change of at least 5 % above every
/// earlier session's (docs/studies.md, "Learners and practice plans").
///
/// Offline code: any thread but the servo thread.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/analysis/trial_score.hpp"
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
  bool disturbed = false;    ///< the loop disturbed it (kept, flagged): shown, not compared
  double shape = 0.0;        ///< DTW x + y (lower: closer to the model)
  double force = 0.0;        ///< DTW fx + fy + fz
  analysis::TrialScore score;  ///< every channel's cost (for a ScoreCache)
  double writing_time_s = 0.0;
  double pen_lifts = 0.0;
  double velocity_peaks = 0.0;  ///< speed changes: fewer is smoother
  bool best = false;         ///< the lowest shape cost of its letter's compared trials
  bool latest = false;       ///< its letter's last compared trial
};

struct ProgressSession {
  int session = 1;           ///< from 1
  int day = 0;               ///< the plan's day offset
  std::string date;          ///< when it was written (its first trial's local date); "" before
  int planned = 0;
  int completed = 0;
  int guided = 0;            ///< completed guided trials
  int alone = 0;             ///< completed trials written alone
  double alone_shape = 0.0;  ///< the letters' mean shape costs of the compared trials, averaged (NaN: none)
  bool is_start = false;     ///< this session is where the learner starts (no change)
  double change = 0.0;       ///< the shape's change from the start, by letter (+0.2: 20 % closer; NaN)
  bool best_so_far = false;  ///< a change of at least 5 % above every earlier session's
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
  bool compares_alone = true; ///< the trials written alone are compared (false: the plan has none)
  std::vector<ProgressSession> sessions;
  std::vector<ProgressTrial> trials;  ///< completed ones, in the order written
};

/// Scores already computed, by trial id: a view that reads the progress again and again (the
/// studio's Learners tab) scores only the trials that are new.
using ScoreCache = std::map<std::int64_t, analysis::TrialScore>;

/// The progress of `subject` (the only one when empty). Throws InputError naming the study and
/// its subjects for an unknown subject, or none named in a study of several.
[[nodiscard]] LearnerProgress learnerProgress(const session::StudyDatabase& db, const std::string& subject = "",
                                              const ScoreCache* scored = nullptr);

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
