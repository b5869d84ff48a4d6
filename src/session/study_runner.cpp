#include "hattr/session/study_runner.hpp"

#include <algorithm>
#include <chrono>
#include <random>
#include <thread>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/io/profile_csv.hpp"

namespace hattr::session {
namespace {

/// A hand script shifted by an offset drawn per trial.
class ScriptParticipant final : public Participant {
 public:
  ScriptParticipant(HapticProfile script, double jitter_m, std::uint64_t seed)
      : script_(std::move(script)), jitter_m_(jitter_m), seed_(seed) {}

  device::HandScript& handForTrial(const TrialPlan& plan) override {
    std::mt19937_64 rng(seed_ * 1'000'003ULL + static_cast<std::uint64_t>(plan.sequence));
    std::uniform_real_distribution<double> offset(-jitter_m_, jitter_m_);
    hand_ = std::make_unique<device::ProfileHandScript>(script_, 1.0471975511965976, Vec3(offset(rng), offset(rng), 0.0));
    return *hand_;
  }
  void trialCompleted(const TrialPlan&, const HapticProfile&) override {}

 private:
  HapticProfile script_;
  double jitter_m_;
  std::uint64_t seed_;
  std::unique_ptr<device::ProfileHandScript> hand_;
};

}  // namespace

std::unique_ptr<Participant> makeScriptParticipant(const SubjectRecord& subject, const HapticProfile& expert) {
  const auto& options = subject.spec.options;
  HapticProfile script = options.contains("hand") ? io::readProfileCsv(options["hand"].get<std::string>()) : expert;
  const double jitter_mm = options.value("jitter_mm", 0.0);
  HATTR_THROW_UNLESS(jitter_mm >= 0.0 && jitter_mm <= 50.0, "subject {}: options.jitter_mm: expected 0 to 50, got {}",
                     subject.id, jitter_mm);
  return std::make_unique<ScriptParticipant>(std::move(script), jitter_mm / 1000.0, subject.spec.seed);
}

/// One subject's participants, one per skill, each made when its skill's first trial comes;
/// the days between sessions reach every one made so far.
class StudyRunner::SubjectParticipants {
 public:
  SubjectParticipants(const StudyRunner& runner, const SubjectRecord& subject) : runner_(runner), subject_(subject) {}
  Participant& of(const std::string& skill) {
    auto& participant = by_skill_[skill];
    if (!participant) participant = runner_.factory_(subject_, runner_.experts_.at(skill));
    return *participant;
  }
  /// The schedule's day of the next trial: the days since the last trial's pass for every
  /// participant made so far (the first trial passes none).
  void moveToDay(int day) {
    if (day_ && day > *day_) {
      for (auto& [skill, participant] : by_skill_) participant->daysPassed(day - *day_);
    }
    day_ = day;
  }

 private:
  std::optional<int> day_;
  const StudyRunner& runner_;
  const SubjectRecord& subject_;
  std::map<std::string, std::unique_ptr<Participant>> by_skill_;
};

StudyRunner::StudyRunner(StudyDatabase& db, ParticipantFactory factory) : db_(db), factory_(std::move(factory)) {
  const StudyDefinition& study = db_.study();
  for (const auto& [skill, file] : study.experts) experts_.emplace(skill, db_.expert(skill));
  world_ = render::parseWorldConfig(study.world.dump(), "study world");
  for (const auto& [skill, expert] : experts_) {
    references_[skill] = std::make_shared<guidance::ReferenceTrajectory>(expert, study.rate_hz);
  }
}

int StudyRunner::run(const RunOptions& options) {
  HATTR_THROW_UNLESS(options.mentor != nullptr || !db_.study().hasMentoredModes(),
                     "study \"{}\" has mentored modes: their training trials need the expert's station (the study "
                     "file's mentor block), which this app did not provide", db_.study().name);
  HATTR_THROW_UNLESS(options.subjects_at_once >= 1, "subjects at once: expected at least 1, got {}",
                     options.subjects_at_once);
  stopping_ = false;
  waiting_.clear();
  if (options.environment) {
    const StudyDefinition& study = db_.study();
    HATTR_DEMAND(options.environment->deviceUri() == study.device && options.environment->rate_hz() == study.rate_hz,
                 "RunOptions::environment: made for {} at {} Hz, the study runs {} at {} Hz",
                 options.environment->deviceUri(), options.environment->rate_hz(), study.device, study.rate_hz);
  }
  environment_.given = options.environment;
  int ran = 0;
  for (;;) {
    held_elsewhere_ = false;
    ran += runEverySubjectOnce(options, ran);
    const bool budget_left = options.max_trials < 0 || ran < options.max_trials;
    if (!held_elsewhere_ || stopping_ || !budget_left) return ran;
    // Other stations (PostgreSQL) hold subjects with trials left: ask again later, and take
    // over any whose station stops renewing its lease.
    std::this_thread::sleep_for(std::chrono::duration<double>(db_.claimRetryInterval_s()));
  }
}

int StudyRunner::runEverySubjectOnce(const RunOptions& options, int ran_before) {
  const std::vector<SubjectRecord> subjects = db_.subjects();
  // Only the in-process simulated pen: any other device runs in real time (runTrial), and a
  // person or a plugin's device is one at a time.
  const bool simulated_pen = device::parseDeviceUri(db_.study().device).scheme == "sim";
  if (options.subjects_at_once > 1 && simulated_pen && options.clock == Clock::kSimulated &&
      options.mentor == nullptr && options.max_trials < 0 && options.only_subject.empty()) {
    return runSubjectsAtOnce(subjects, options);
  }
  int ran = 0;
  bool found = options.only_subject.empty();
  for (const SubjectRecord& subject : subjects) {
    if (!options.only_subject.empty() && subject.id != options.only_subject) continue;
    found = true;
    const int budget = options.max_trials < 0 ? -1 : options.max_trials - ran_before - ran;
    if (budget == 0) break;
    ran += runSubject(subject, options, budget, environment_);
  }
  HATTR_THROW_UNLESS(found, "--subject {}: no such subject in the study", options.only_subject);
  return ran;
}

int StudyRunner::runSubjectsAtOnce(const std::vector<SubjectRecord>& subjects, const RunOptions& options) {
  // Workers take the subjects in turn; each keeps its own paper and device.
  std::atomic<std::size_t> next{0};
  std::atomic<int> ran{0};
  std::exception_ptr failure;
  const auto work = [&](EnvironmentSlot& environment) {
    try {
      for (std::size_t s = next++; s < subjects.size() && !stopping_; s = next++) {
        ran += runSubject(subjects[s], options, -1, environment);
      }
    } catch (...) {
      const std::lock_guard lock(db_mutex_);
      if (!failure) failure = std::current_exception();
      stopping_ = true;
    }
  };
  const auto workers_wanted = std::min<std::size_t>(static_cast<std::size_t>(options.subjects_at_once), subjects.size());
  std::vector<EnvironmentSlot> environments(workers_wanted);
  std::vector<std::thread> workers;
  try {
    for (std::size_t w = 1; w < workers_wanted; ++w) workers.emplace_back(work, std::ref(environments[w]));
  } catch (...) {  // no thread for this one: the others stop, and the error is the run's
    stopping_ = true;
    for (auto& worker : workers) worker.join();
    throw;
  }
  work(environment_);
  for (auto& worker : workers) worker.join();
  if (failure) std::rethrow_exception(failure);
  return ran;
}

TrialEnvironment& StudyRunner::environmentOf(EnvironmentSlot& slot) const {
  if (slot.given) return *slot.given;
  if (!slot.made) slot.made = std::make_unique<TrialEnvironment>(db_.study().device, world_, db_.study().rate_hz);
  return *slot.made;
}

HapticProfile StudyRunner::storedProfile(std::int64_t trial_id) {
  return withDatabase([trial_id](StudyDatabase& db) { return db.trialProfile(trial_id); });
}

// Every use of the database goes through withDatabase: other subjects may run beside this one.
int StudyRunner::runSubject(const SubjectRecord& subject, const RunOptions& options, int budget,
                            EnvironmentSlot& environment) {
  std::vector<TrialRecord> trials = withDatabase([&](StudyDatabase& db) { return db.trials(subject.id); });
  // A finished subject costs nothing: no participant is made and nothing is relived.
  const auto left = std::count_if(trials.begin(), trials.end(),
                                  [](const TrialRecord& t) { return t.status != TrialStatus::kCompleted; });
  if (left == 0) return 0;
  if (stopping_) return 0;  // another subject's trial failed meanwhile

  // The subject, for this runner alone (on PostgreSQL another station may hold it), and its
  // trials as they are now that it is ours; given back however this ends.
  const SubjectClaim claim = withDatabase([&](StudyDatabase& db) { return db.claimSubject(subject.id); });
  if (!claim.granted) {
    if (!options.only_subject.empty()) {  // not bad input: the study's state at this moment
      throw Error(fmt::format("--subject {}: another station is running this subject ({}); run another subject, or "
                              "wait for it", subject.id, claim.holder));
    }
    held_elsewhere_ = true;
    return 0;
  }
  struct Release {
    StudyRunner& runner;
    const std::string& subject;
    ~Release() {
      try {
        runner.withDatabase([this](StudyDatabase& db) { db.releaseSubject(subject); });
      } catch (const std::exception&) {  // the lease lapses on its own
      }
    }
  } release{*this, subject.id};
  trials = withDatabase([&](StudyDatabase& db) { return db.trials(subject.id); });
  if (std::all_of(trials.begin(), trials.end(), [](const TrialRecord& t) { return t.status == TrialStatus::kCompleted; })) {
    return 0;  // another station finished it meanwhile
  }
  SubjectParticipants participants(*this, subject);
  SubjectTrials steps(db_.study(), subject, std::move(trials), references_);
  if (db_.scratch()) steps.skipKinematics();

  // Resume: the participants relive the trials already done, in order.
  relivePassed(steps, participants);
  if (!dueNow(subject, steps, options)) return 0;
  const std::int64_t session = withDatabase([&](StudyDatabase& db) { return db.beginSession(subject.id); });
  int ran = 0;
  try {
    runTrialsLeft(subject, options, budget, environment, steps, participants, session, ran);
  } catch (const SubjectTakenOver&) {
    // Another station took the subject over (this one's lease lapsed): it runs the rest.
    held_elsewhere_ = true;
    withDatabase([&](StudyDatabase& db) { db.endSession(session); });
    return ran;
  }
  withDatabase([&](StudyDatabase& db) { db.endSession(session); });
  return ran;
}

void StudyRunner::relivePassed(SubjectTrials& steps, SubjectParticipants& participants) {
  for (const TrialRecord& done : steps.passCompleted()) {
    participants.moveToDay(done.plan.day);
    participants.of(done.plan.skill).trialCompleted(done.plan, storedProfile(done.id));
  }
}

bool StudyRunner::dueNow(const SubjectRecord& subject, const SubjectTrials& steps, const RunOptions& options) {
  if (!options.follow_calendar || steps.current() == nullptr) return true;
  const std::vector<TrialRecord> trials = withDatabase([&](StudyDatabase& db) { return db.trials(subject.id); });
  const SubjectSchedule schedule = subjectSchedule(db_.study(), trials, options.today.value_or(localToday()));
  if (schedule.runnable()) return true;
  withDatabase([&](StudyDatabase&) {
    waiting_.push_back({subject.id, schedule});
    return 0;
  });
  return false;
}

void StudyRunner::runTrialsLeft(const SubjectRecord& subject, const RunOptions& options, int budget,
                                EnvironmentSlot& environment, SubjectTrials& steps, SubjectParticipants& participants,
                                std::int64_t session, int& ran) {
  const StudyDefinition& study = db_.study();
  const std::filesystem::path rescue_folder =
      options.rescue_folder.empty() ? defaultRescueFolder(db_) : options.rescue_folder;
  for (;;) {
    if ((budget >= 0 && ran >= budget) || stopping_) break;
    // A trial completed after a gap (an earlier one left pending) is never run again: the
    // participant relives it in its place, as on resume.
    relivePassed(steps, participants);
    if (steps.current() == nullptr) break;
    // A session on a later day: the days pass (simulated), or the run waits for its date.
    if (steps.daysBefore() > 0 && !dueNow(subject, steps, options)) break;
    participants.moveToDay(steps.current()->plan.day);
    const TrialRecord record = *steps.current();
    const TrialPlan& plan = record.plan;
    Participant& participant = participants.of(plan.skill);
    if (steps.restBefore()) participant.rest(steps.restSeconds());
    participant.prompt(steps.prompt());

    // The trial, set up as every app sets up a study trial, on the runner's clock; a disturbed
    // one is kept and run again while the policy says so.
    TrialResult result;
    SubjectTrials::Outcome outcome;
    do {
      TrialSetup setup = steps.setup(options.clock, options.mentor);
      setup.inject_stall_at_s =
          options.inject_stall_at_s
              ? withDatabase([&](StudyDatabase&) { return options.inject_stall_at_s(plan, steps.attempt()); })
              : -1.0;
      withDatabase([&](StudyDatabase& db) { steps.begin(db, session); });
      result = runTrial(environmentOf(environment), setup, participant.handForTrial(plan));
      steps.measure(result);  // beside the other subjects, not under the database's lock
      outcome = withDatabase([&](StudyDatabase& db) { return steps.end(db, result, rescue_folder); });
      // A trial the device broke off is not data: marked failed, everything stored kept, and the run stops.
      if (outcome.ending == SubjectTrials::Ending::kFailed) {
        withDatabase([&](StudyDatabase& db) { db.endSession(session); });
        throw Error(fmt::format("subject {}: {} trial {} with {} failed: {}; completed trials are kept, and `study "
                                "run` repeats this one",
                                subject.id, plan.phase, plan.index, guidance::modeName(plan.mode),
                                result.failure));
      }
      if (outcome.ending == SubjectTrials::Ending::kRepeat) {
        participant.prompt(fmt::format("That trial was disturbed ({}): once more", outcome.disturbed));
      }
    } while (outcome.ending == SubjectTrials::Ending::kRepeat);

    // The participant learns from what was stored (at a declared resolution, not what was
    // measured), as it does on resume: a resumed study stays bit-identical.
    const HapticProfile stored = study.resolution.empty() ? HapticProfile() : storedProfile(record.id);
    const HapticProfile& as_stored = study.resolution.empty() ? result.profile : stored;
    participant.trialCompleted(plan, as_stored);
    if (options.stored) options.stored(outcome.trial, as_stored);
    if (study.protocol.show_scores && options.score_text) {
      participant.prompt(withDatabase([&](StudyDatabase&) { return options.score_text(plan, result.profile); }));
    }
    ++ran;
    if (options.progress) {
      withDatabase([&](StudyDatabase&) {  // one progress call at a time
        options.progress({subject.id, static_cast<int>(steps.position()), steps.totalCount(), &outcome.trial});
      });
    }
  }
}

}  // namespace hattr::session
