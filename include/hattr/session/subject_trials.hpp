#pragma once
/// One subject's trials in a study, a trial at a time: the protocol that StudyRunner (every
/// trial in one call) and the studio's study session (a person, one trial when they are ready)
/// both step through. It knows which trial comes next (resuming at the first not completed),
/// whether a rest comes before it, its prompt, its set-up and its attempt, and it decides what
/// becomes of a trial when it ends: stored, kept as a disturbed attempt and run again, or marked
/// failed. The caller runs the trial, keeps the database session, and passes the database it
/// holds (StudyRunner's lock) to the calls that write.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "hattr/session/study_database.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::session {

/// The metadata keys of a trial's kinematics start with this ("kinematics.duration_s").
inline constexpr const char* kKinematicsPrefix = "kinematics.";

/// Each skill's expert reference at the study's rate.
using StudyReferences = std::map<std::string, std::shared_ptr<const guidance::ReferenceTrajectory>>;
/// Every expert of the study database as a reference at the study's rate.
StudyReferences studyReferences(const StudyDatabase& db);

/// The set-up of one study trial, as every app runs it (through SubjectTrials::setup): the
/// mode's guidance in training, none (BASIC) in recall, the study's indexing, `reference` (the
/// expert of the trial's skill at the study's rate); the end: protocol.trial_end (the pen lifted for pen_up_s
/// after writing began, at most maxDuration_s of the expert's duration), or for an old study
/// file with protocol.fixed_window the expert's duration plus tail_s and no end rule; the study
/// metadata (subject = plan.subject, skill, source "study:<name>", study_mode, phase, trial,
/// sequence, reference_shown; for a design not of the paper's form also group, session, day
/// and block). Throws InputError when `reference` is null.
TrialSetup studyTrialSetup(const StudyDefinition& study, const TrialPlan& plan,
                           std::shared_ptr<const guidance::ReferenceTrajectory> reference);

/// The seed of a mentored trial's link (LiveGuidance::beginTrial): a simulated mentor's link
/// draws the same losses for the same trial and attempt, resumed or not, in every app.
std::uint64_t studyLiveSeed(const SubjectSpec& subject, const TrialPlan& plan, int attempt);

/// Whether a study runs a disturbed trial again: the policy is "repeat" and it has been
/// repeated fewer than protocol.max_repeats times.
bool repeatDisturbedTrial(const Protocol& protocol, const std::string& disturbed, int repeats_so_far);

/// Where a study's refused recordings go when no folder is given: beside a study file
/// (FILE.unstored/), or for a PostgreSQL study ./hattr-unstored/.
std::filesystem::path defaultRescueFolder(const StudyDatabase& db);

class SubjectTrials {
 public:
  /// `trials`: the subject's trials as StudyDatabase::trials lists them; `study` (the
  /// database's) must outlive this. Positioned at the first trial; passCompleted() moves past
  /// those already done.
  /// `references` must hold every skill of the subject's trials.
  SubjectTrials(const StudyDefinition& study, SubjectRecord subject, std::vector<TrialRecord> trials,
                StudyReferences references);

  /// Moves past the completed trials at the current position (on resume, or a trial completed
  /// after a gap, which is never run again) and returns them in order: a simulated trainee
  /// relives them in their place.
  std::vector<TrialRecord> passCompleted();
  /// The trial to run now (also while it runs); null once every trial is completed.
  [[nodiscard]] const TrialRecord* current() const noexcept;
  /// The current trial's index among the subject's trials (the trial count when done).
  [[nodiscard]] std::size_t position() const noexcept { return next_; }
  [[nodiscard]] int completedCount() const noexcept { return completed_; }
  [[nodiscard]] int totalCount() const noexcept { return static_cast<int>(trials_.size()); }
  /// A rest comes before the current trial's first attempt: before every trial but the first
  /// of each session, resumed or not.
  [[nodiscard]] bool restBefore() const noexcept;
  /// The rest before the current trial [s]: its block's.
  [[nodiscard]] double restSeconds() const;
  /// Days of the schedule between the previous trial's session and the current one's (0 within
  /// a session, and before the first trial).
  [[nodiscard]] int daysBefore() const noexcept;
  /// The current trial's attempt: 0, then one more for each disturbed attempt run again.
  [[nodiscard]] int attempt() const noexcept { return attempt_; }
  /// How a prompt names the strategy and the phase: technically ("Training with ALPHA",
  /// "Post-test"), or as a teacher and a learner read it ("Training with Guided pressure",
  /// "Written alone"; the baseline is "Before practice", retention "Written alone, days later",
  /// transfer "A new letter"; other phases as they are).
  enum class Wording { kTechnical, kPlain };
  /// "Training with ALPHA: trial 3 of 11", "Retention: trial 2 of 5". Needs a current trial.
  [[nodiscard]] std::string prompt(Wording wording = Wording::kTechnical) const;
  /// The current attempt's set-up (studyTrialSetup) on `clock`, with the mentored modes' expert
  /// station and its link's seed; for a scheduled strategy's guided trial, the law and gain its
  /// schedule gives from the tracking errors stored with the subject's guided trials of the same
  /// strategy before it (guidance::scheduleTrial). The caller sets the settle time, the stop
  /// request and any injected stall.
  [[nodiscard]] TrialSetup setup(Clock clock, LiveGuidance* mentor) const;

  /// Marks the current trial running in `session` (each call counts an attempt in the database).
  void begin(StudyDatabase& db, std::int64_t session) const;

  enum class Ending {
    kStored,  ///< stored with its profile; the position moved to the next trial
    kRepeat,  ///< disturbed: kept as an attempt, and the same trial runs again (attempt() + 1)
    kFailed,  ///< the device or the mentor broke it off: marked failed, nothing stored
  };
  struct Outcome {
    Ending ending = Ending::kStored;
    std::string disturbed;  ///< disturbanceOf the trial ("" when clean)
    TrialRecord trial;      ///< the trial as it is now (completed when stored)
  };
  /// The current trial ended with `result` (clearing its created_utc and noting its loop's
  /// counters, so a resumed study stays bit-identical; a scheduled strategy's guided trial gets
  /// its tracking error, tracking_rms_m, in its metadata). A failure is marked failed; a disturbed
  /// trial the policy repeats is kept as an attempt; any other is stored with its outcome text.
  /// When the store refuses it the recording is written to `rescue_folder` (a profile CSV) and an
  /// Error says where; the trial stays running, to be run again. Throws SubjectTakenOver when
  /// another station took the subject over, and Error for an empty recording (nothing to store).
  Outcome end(StudyDatabase& db, TrialResult& result, const std::filesystem::path& rescue_folder);
  /// The part of end() that needs no database, which a caller holding a lock for end() may do
  /// before taking it, once per trial: every trial gets its handwriting kinematics in its
  /// metadata (kKinematicsPrefix + each of analysis::kinematicsNames(), "NA" where not a
  /// number), and a scheduled strategy's guided trial its tracking error (tracking_rms_m).
  void measure(TrialResult& result) const;
  /// From now on measure() leaves out the handwriting kinematics: for a scratch study (a power
  /// analysis's replicate), whose analysis reads none.
  void skipKinematics() noexcept { kinematics_ = false; }
  /// The current trial failed (why): marked failed in the database; its next run is attempt 0.
  void fail(StudyDatabase& db, const std::string& reason);

 private:
  /// Stores a finished trial, or, when the store refuses it, keeps its recording in a file
  /// and throws an Error saying where.
  static void storeOrRescue(StudyDatabase& db, const TrialRecord& record, const HapticProfile& profile,
                            const std::string& outcome, const std::string& disturbed,
                            const std::filesystem::path& rescue_folder);

  /// A guided trial of a scheduled strategy.
  static bool scheduledTrial(const TrialPlan& plan) noexcept;
  /// The tracking errors of the current trial's scheduled strategy's guided trials before it.
  [[nodiscard]] std::vector<double> scheduledErrorsBefore() const;

  const StudyDefinition& study_;
  SubjectRecord subject_;
  std::vector<TrialRecord> trials_;
  StudyReferences references_;
  std::size_t next_ = 0;  // index of the current trial in trials_
  int completed_ = 0;
  int attempt_ = 0;
  bool kinematics_ = true;  ///< measure() adds the kinematics (skipKinematics)
};

}  // namespace hattr::session
