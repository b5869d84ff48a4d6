#pragma once
/// A person's study session at the studio: session::StudyRunner's protocol, stepped by the
/// GUI instead of run in one call, because a person needs to see the pen, rest between trials
/// and start each trial when ready. The steps are the library's session::SubjectTrials, which
/// the runner steps too: resume at the first trial not completed, rests, prompts, each trial's
/// set-up, the trial marked running before it starts, and at its end stored (or rescued to a
/// file when the store refuses it), kept as a disturbed attempt and run again, or marked
/// failed. What is the studio's own: the database opened as the runner opens it (exclusive
/// lock, trials left running marked interrupted), the rest's countdown, and the state the
/// panel shows.
///
/// A study with mentored modes gets its expert's station from the study file's mentor
/// block (net::makeStudyMentor), as `hattr study run` does: currentSetup() hands it to the
/// trial as its live guidance, and a trial whose mentor was not there fails (failTrial).
///
/// GUI thread only; times are seconds of any monotonic clock the caller keeps.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hattr/session/study_database.hpp"
#include "hattr/session/study_schedule.hpp"
#include "hattr/session/subject_trials.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::studio {

class StudySession {
 public:
  enum class State {
    kNoSubject,  ///< no subject picked yet
    kResting,    ///< the rest before the next trial is counting down
    kReady,      ///< the next trial waits for the person (prompt shown)
    kRunning,    ///< a trial is running (marked running in the database)
    kNextSession,  ///< a session of the schedule is over: the next waits to be begun (schedule())
    kFinished,   ///< every trial of the subject is completed
  };

  /// Opens a study database as its runner. Throws InputError for a file that is not a
  /// hattr study, a newer schema, a study another runner holds (naming the holder), or a
  /// mentor block that cannot be set up (a live mentor's address or key file).
  explicit StudySession(const std::filesystem::path& file);
  /// Ends the session in the database if one was begun.
  ~StudySession();
  StudySession(const StudySession&) = delete;
  StudySession& operator=(const StudySession&) = delete;

  [[nodiscard]] const session::StudyDefinition& study() const noexcept { return db_.study(); }
  [[nodiscard]] const std::filesystem::path& file() const noexcept { return db_.file(); }
  [[nodiscard]] std::vector<session::SubjectRecord> subjects() const { return db_.subjects(); }
  /// The expert of the current trial's skill (the study's skill when there is none).
  [[nodiscard]] const HapticProfile& expert() const;
  /// The reference of the current trial's skill (the study's skill when there is none).
  [[nodiscard]] const std::shared_ptr<const guidance::ReferenceTrajectory>& reference() const;
  /// The study's device, paper and rate, built as the runner builds them.
  [[nodiscard]] session::TrialEnvironment& environment() noexcept { return *environment_; }

  /// Picks the subject and resumes at its first trial not completed. The runner's rule:
  /// a rest comes before every trial but the first of a session. A session not begun yet
  /// after an earlier one waits to be begun (kNextSession). Throws InputError for an
  /// unknown subject; not while a trial runs.
  void selectSubject(const std::string& subject_id, double now_s);
  [[nodiscard]] const std::string& subject() const noexcept { return subject_; }
  /// The subject's participant kind ("person" is the one meant for the studio).
  [[nodiscard]] std::string participantKind() const;

  /// Where a subject stands in the schedule today (session::subjectSchedule): its next
  /// session, due, early or overdue. The current subject when `subject_id` is empty.
  [[nodiscard]] session::SubjectSchedule schedule(const std::string& subject_id = "") const;
  /// Begins the next session (from kNextSession): ready for its first trial, whatever its due
  /// date (the caller asks the person first when schedule() says it is early).
  void beginNextSession();

  /// Moves from resting to ready when the rest is over.
  void tick(double now_s);
  /// Ends the rest now (the experimenter's "next").
  void skipRest();
  [[nodiscard]] State state() const noexcept { return state_; }
  [[nodiscard]] double restRemaining_s(double now_s) const noexcept;

  /// The trial the subject does next (also while it runs), if any.
  [[nodiscard]] const session::TrialRecord* currentTrial() const noexcept;
  /// The runner's prompt for the current trial ("Training with ALPHA: trial 3 of 11"); between
  /// sessions, the next one ("Next session for S07: session 2 of 3 (day 1), due today").
  [[nodiscard]] std::string prompt(session::SubjectTrials::Wording wording = session::SubjectTrials::Wording::kTechnical) const;
  /// The runner's set-up of the current trial (session::studyTrialSetup: guidance on in
  /// training, BASIC in recall, the study's end rule and maximum — or an old file's fixed
  /// window —, the study metadata), on the real-time clock. The caller sets the settle time
  /// (the person's "get ready") and the stop request.
  [[nodiscard]] session::TrialSetup currentSetup() const;
  [[nodiscard]] int completedCount() const noexcept { return trials_ ? trials_->completedCount() : 0; }
  [[nodiscard]] int totalCount() const noexcept { return trials_ ? trials_->totalCount() : 0; }

  /// Starts the current trial: begins the session if needed, marks the trial running.
  /// Only when ready (or resting: the rest is cut short).
  void beginTrial();
  /// The trial ended (session::SubjectTrials::end): stored, and on to a rest before the next
  /// trial, to the next session (the session ends) or to finished; or, disturbed with the "repeat" policy, kept as
  /// an attempt and back to ready for the same trial. Throws hattr::Error for an empty
  /// recording or when the database refuses the write (the recording is then kept in the
  /// study's rescue folder, and the error says where); either way the state goes back to ready
  /// and the trial (still marked running) can be run again. A failed result is failTrial's.
  /// Returns the disturbance ("" when clean).
  std::string completeTrial(session::TrialResult result, double now_s);
  /// The trial failed (the device or its mentor broke it off; session::TrialResult::failure):
  /// marked failed with the reason, as the runner marks it, and back to ready to run it again.
  void failTrial(const std::string& reason);
  /// The person abandoned the trial: it stays marked running until run again (each run
  /// counts an attempt; a crash leaves it to be marked interrupted). Back to ready.
  void abandonTrial();

 private:
  session::StudyDatabase db_;
  std::map<std::string, HapticProfile> experts_;  // skill -> expert
  std::unique_ptr<session::TrialEnvironment> environment_;
  session::StudyReferences references_;
  std::unique_ptr<session::LiveGuidance> mentor_;  ///< the mentored modes' expert station
  std::string subject_;
  std::optional<session::SubjectTrials> trials_;  // the subject's, once picked
  std::optional<std::int64_t> session_id_;
  /// The state for the current trial once the trials before it are done: ready, or the next
  /// session when it begins one that has not begun.
  [[nodiscard]] State stateBeforeSession() const;
  State state_ = State::kNoSubject;
  double rest_until_s_ = 0.0;
};

std::string_view stateName(StudySession::State state);

}  // namespace hattr::studio
