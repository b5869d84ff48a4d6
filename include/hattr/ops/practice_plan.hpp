#pragma once
/// A learner's practice plan (a teacher's or therapist's, in the studio or `hattr learner`):
/// the `learner` design of `hattr study example` made for one person, some letters, one
/// training strategy and a number of sessions, as a study database of its own.
///
/// Each session, for each letter: `trials_per_session` trials with the strategy's guidance and
/// the model letter shown (phase "training"), then `check_trials` written alone from memory
/// (phase "post-test": no guidance, the model hidden). The first session begins with
/// `check_trials` written alone with the model shown (phase "baseline": where the learner
/// starts). Sessions fall `days_between` days apart; with `retention_after_days` > 0, one more
/// session of `check_trials` per letter (phase "retention") that many days after the last.
/// Every letter's expert is the simulated expert writing the glyph on the plan's pen.
///
/// Plans live in a practice folder, one folder per learner named by their code:
///   FOLDER/<code>/plan-1.sqlite, plan-2.sqlite, ...
/// docs/studio.md, "For teachers", shows it in use.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/guidance/training_guidance.hpp"
#include "hattr/session/learner.hpp"
#include "hattr/session/study_schedule.hpp"

namespace hattr::ops {

struct PracticePlanOptions {
  session::Learner learner;
  std::vector<std::string> letters;  ///< glyphs by character ("a"), built-in name or .json file
  guidance::TrainingMode strategy = guidance::TrainingMode::kPositionControl;
  int sessions = 6;                  ///< 1 to 60
  int trials_per_session = 8;        ///< guided trials per letter and session, 1 to 100
  int check_trials = 3;              ///< unguided trials per letter and session, 0 to 20
  int days_between = 2;              ///< 0 to 30
  int retention_after_days = 7;      ///< 0: no retention session; else 1 to 90
  double rest_s = 5.0;               ///< between trials, 0 to 600
  std::string device = "sim://pen";
};

/// The plan's study definition (the letters' experts not yet recorded). Throws InputError
/// listing every problem of the options, one a line (the learner's too: learnerProblems).
[[nodiscard]] session::StudyDefinition practicePlanStudy(const PracticePlanOptions& options);

/// Makes a plan in `folder`: FOLDER/<code>/plan-N.sqlite, N the first number not taken (the
/// folders are created; InputError when they cannot be). The experts are recorded first, so
/// nothing is left behind when a letter cannot be written. Returns the new file.
std::filesystem::path createPracticePlan(const std::filesystem::path& folder, const PracticePlanOptions& options);

/// One plan in a practice folder, as the learners' list shows it.
struct PracticePlanSummary {
  std::filesystem::path file;
  session::Learner learner;
  std::string name;                   ///< the plan's (the study's) name
  std::vector<std::string> letters;   ///< as written (session::letterName), in plan order
  guidance::TrainingMode strategy = guidance::TrainingMode::kBasic;
  int trials_total = 0;
  int trials_completed = 0;
  session::SubjectSchedule schedule;  ///< on `today`
};

/// One plan's summary on `today`. InputError for a file that is not a study, or a study that is
/// not one learner's (naming what it has).
[[nodiscard]] PracticePlanSummary summarizePracticePlan(const std::filesystem::path& file,
                                                        const session::LocalDate& today);

/// Every plan of a practice folder, by learner code then plan number. InputError for a folder
/// that is not there or cannot be read. A plan-N.sqlite that is not a practice plan (not a
/// study, or not of one learner), and a learner's folder that cannot be read, are skipped and
/// named in `skipped`.
[[nodiscard]] std::vector<PracticePlanSummary> listPracticePlans(const std::filesystem::path& folder,
                                                                 const session::LocalDate& today,
                                                                 std::vector<std::string>* skipped = nullptr);

[[nodiscard]] nlohmann::json toJson(const PracticePlanSummary& plan);

}  // namespace hattr::ops
