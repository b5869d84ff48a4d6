#pragma once
/// Runs a study's design: subject → session → block (its strategy from the subject's
/// counterbalanced order where it says so) → trials, with rests, each trial through runTrial
/// and stored the moment it ends. The same code runs a simulated trainee, a person at the
/// studio or a person on a real device: what differs is the Participant. Sessions on later
/// days wait for their date when the run follows the calendar; in simulated days they follow
/// at once, and the participant is told how many days passed.

#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "hattr/session/study_database.hpp"
#include "hattr/session/study_schedule.hpp"
#include "hattr/session/subject_trials.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::session {

/// Who does the trials.
class Participant {
 public:
  virtual ~Participant() = default;
  /// The hand that will hold the (simulated) pen in this trial; a person on a real device
  /// returns a hand whose commands the device ignores.
  virtual device::HandScript& handForTrial(const TrialPlan& plan) = 0;
  /// Called once per trial after it is stored (a simulated trainee learns here). Also used
  /// on resume to replay the completed trials, so it must be deterministic.
  virtual void trialCompleted(const TrialPlan& plan, const HapticProfile& recorded) = 0;
  /// The rest between trials (a person sees a countdown; a simulation does nothing).
  virtual void rest(double /*seconds*/) {}
  /// A prompt for the person ("Training with ALPHA: trial 3 of 11").
  virtual void prompt(const std::string& /*text*/) {}
  /// The schedule moved on `days` days (> 0) since the last trial: the next session is on a
  /// later day (a simulated trainee forgets, docs/simulation.md). Also on resume, in order.
  virtual void daysPassed(int /*days*/) {}
};

/// Makes the participant for a subject learning one skill, from that skill's expert (the app
/// decides which kinds exist). A study of several skills makes one per skill the subject
/// writes, each when its first trial comes.
using ParticipantFactory =
    std::function<std::unique_ptr<Participant>(const SubjectRecord& subject, const HapticProfile& expert)>;

/// A participant that plays a hand script from its options ({"hand": "file.csv"}, or the
/// expert's own profile when absent), with an optional seeded offset drawn per trial
/// ({"jitter_mm": 0.5}); it does not learn. For tests and scripted demonstrations.
std::unique_ptr<Participant> makeScriptParticipant(const SubjectRecord& subject, const HapticProfile& expert);

struct RunProgress {
  std::string subject;
  int completed = 0;   ///< trials completed for this subject so far
  int total = 0;
  const TrialRecord* trial = nullptr;
};

struct RunOptions {
  std::string only_subject;                           ///< run only this subject ("" = all)
  Clock clock = Clock::kSimulated;
  std::function<void(const RunProgress&)> progress;   ///< after each trial
  int max_trials = -1;                                ///< stop after this many trials (-1: all)
  /// A score for the subject after each trial, shown (as a prompt) only when the study's
  /// protocol.show_scores asks; the app supplies it (the runner does not score).
  std::function<std::string(const TrialPlan&, const HapticProfile&)> score_text;
  /// Rehearsing the disturbed-trial policy on the simulator: the trial time at which a host
  /// stall is injected into an attempt (attempt 0 is the first), negative for none.
  std::function<double(const TrialPlan&, int attempt)> inject_stall_at_s;
  /// The expert's station for the training trials of mentored modes (net::makeStudyMentor);
  /// required when the study has one, and such a trial is refused without it.
  LiveGuidance* mentor = nullptr;
  /// Subjects run at once, each on its own thread with its own paper and device, the database
  /// written one trial at a time: the trials are the same to the bit as one subject at a time
  /// (each subject's trials depend only on that subject). Only on the simulated pen (sim://)
  /// in simulated time, for all subjects, without a mentor or max_trials; otherwise subjects
  /// run one at a time. The callbacks above are then called one at a time (under the
  /// database's lock), and each participant only from its subject's thread.
  int subjects_at_once = 1;
  /// Where a trial's recording goes when the store refuses it (a server away, a full disk), so
  /// that nothing recorded is lost: "" = beside a study file (FILE.unstored/), or for a
  /// PostgreSQL study ./hattr-unstored/. The trial runs again when the study resumes.
  std::filesystem::path rescue_folder;
  /// Sessions on later days wait for their date (subjectSchedule): a subject whose next session
  /// is early is left, and listed in StudyRunner::waiting(). False: the days are simulated, and
  /// every session follows at once.
  bool follow_calendar = false;
  /// Today, for follow_calendar (none: the station's local date).
  std::optional<LocalDate> today;
  /// After each trial is stored, on the thread that ran it (not under the database's lock:
  /// other subjects' trials go on meanwhile), with the trial's record and its profile as
  /// stored: what a caller scores without reading it back (a scratch store keeps no samples).
  std::function<void(const TrialRecord&, const HapticProfile&)> stored;
  /// The paper and device to run on, the caller's (a power analysis reuses one across its
  /// replicates: its texture takes a while to generate); made from the study's device, world
  /// and rate. Used by the calling thread; subjects run at once get their own besides. Null:
  /// the runner makes one at the first trial.
  TrialEnvironment* environment = nullptr;
};

/// A subject left because its next session is not due yet (RunOptions::follow_calendar).
struct WaitingSubject {
  std::string subject;
  SubjectSchedule schedule;
};

class StudyRunner {
 public:
  /// `db` must be opened with OpenMode::kRunner.
  StudyRunner(StudyDatabase& db, ParticipantFactory factory);
  /// Runs every unfinished trial (of one subject, or all), resuming where the study stopped:
  /// a subject with trials left first relives its completed trials (its participant learns
  /// from what was stored); a finished subject costs nothing. Returns trials run now. When a
  /// trial fails, the subjects running beside it stop after their current trial, and the
  /// first failure is thrown. On PostgreSQL each subject is claimed first: subjects other
  /// stations hold are skipped, and the run waits (asking again every quarter of the lease
  /// timeout) until no subject with trials left is held elsewhere, so a lapsed station's
  /// subjects are taken over; `--subject` held elsewhere is an Error naming the holder.
  int run(const RunOptions& options);
  /// The subjects the last run left because their next session is not due yet.
  [[nodiscard]] const std::vector<WaitingSubject>& waiting() const noexcept { return waiting_; }

 private:
  /// The paper and the device of one thread: the caller's (RunOptions::environment), else made
  /// at its first trial (the paper's texture takes a while to generate, and a finished study
  /// needs none).
  struct EnvironmentSlot {
    TrialEnvironment* given = nullptr;
    std::unique_ptr<TrialEnvironment> made;
  };
  TrialEnvironment& environmentOf(EnvironmentSlot& slot) const;
  /// One pass over the subjects (of options.only_subject): each with trials left that this
  /// runner can claim runs to its end; those other stations hold set held_elsewhere_.
  int runEverySubjectOnce(const RunOptions& options, int ran_before);
  class SubjectParticipants;
  int runSubject(const SubjectRecord& subject, const RunOptions& options, int budget, EnvironmentSlot& environment);
  /// The subject's trials left, in its session; counts them in `ran`.
  void runTrialsLeft(const SubjectRecord& subject, const RunOptions& options, int budget, EnvironmentSlot& environment,
                     SubjectTrials& trials, SubjectParticipants& participants, std::int64_t session, int& ran);
  /// The participants relive the completed trials at the current position, in order, and the
  /// days between their sessions.
  void relivePassed(SubjectTrials& trials, SubjectParticipants& participants);
  /// Whether the current trial may run now: always, unless the run follows the calendar and it
  /// begins a session that is not due yet (then the subject is noted in waiting_).
  bool dueNow(const SubjectRecord& subject, const SubjectTrials& trials, const RunOptions& options);
  /// A completed trial's profile as stored (through withDatabase).
  HapticProfile storedProfile(std::int64_t trial_id);
  int runSubjectsAtOnce(const std::vector<SubjectRecord>& subjects, const RunOptions& options);
  /// `f(db_)` with the database to this thread alone.
  template <class F>
  auto withDatabase(F&& f) {
    const std::lock_guard lock(db_mutex_);
    return f(db_);
  }

  StudyDatabase& db_;
  std::mutex db_mutex_;
  std::atomic<bool> stopping_{false};  ///< a trial failed: the other subjects stop
  std::atomic<bool> held_elsewhere_{false};  ///< a subject with trials left is another station's now
  ParticipantFactory factory_;
  render::WorldConfig world_;
  EnvironmentSlot environment_;
  StudyReferences references_;
  std::map<std::string, HapticProfile> experts_;  ///< skill -> expert profile
  std::vector<WaitingSubject> waiting_;
};

}  // namespace hattr::session
