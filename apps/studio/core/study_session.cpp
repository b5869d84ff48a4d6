#include "core/study_session.hpp"

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/net/study_mentor.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/study_runner.hpp"

namespace hattr::studio {

StudySession::StudySession(const std::filesystem::path& file)
    : db_(session::StudyDatabase::open(file, session::OpenMode::kRunner)) {
  // The expert, the environment and the reference, as StudyRunner builds them.
  const session::StudyDefinition& study = db_.study();
  expert_ = db_.expert(study.skill);
  const render::WorldConfig world = render::parseWorldConfig(study.world.dump(), "study world");
  environment_ = std::make_unique<session::TrialEnvironment>(study.device, world, study.rate_hz);
  reference_ = std::make_shared<guidance::ReferenceTrajectory>(expert_, study.rate_hz);
  // The expert's station for the mentored modes' training trials, as `hattr study run`'s.
  if (study.hasMentoredModes()) mentor_ = net::makeStudyMentor(study.mentor, expert_, world, study.rate_hz);
}

StudySession::~StudySession() {
  try {
    if (session_id_) db_.endSession(*session_id_);
  } catch (...) {  // closing must not throw; the session's end time stays empty
  }
}

void StudySession::selectSubject(const std::string& subject_id, double now_s) {
  HATTR_THROW_UNLESS(state_ != State::kRunning, "study: cannot change subject while a trial runs");
  bool found = false;
  for (const session::SubjectRecord& s : db_.subjects()) found = found || s.id == subject_id;
  HATTR_THROW_UNLESS(found, "study {}: no subject \"{}\"", db_.file().string(), subject_id);
  // The subject for this station alone (a PostgreSQL study's other stations may hold it); the
  // one before is given back.
  const session::SubjectClaim claim = db_.claimSubject(subject_id);
  HATTR_THROW_UNLESS(claim.granted, "study {}: subject {} is being run at another station ({}); choose another "
                     "subject, or wait for it", db_.file().string(), subject_id, claim.holder);
  if (!subject_.empty() && subject_ != subject_id) db_.releaseSubject(subject_);
  if (session_id_) {
    db_.endSession(*session_id_);
    session_id_.reset();
  }
  subject_ = subject_id;
  trials_ = db_.trials(subject_id);
  repeats_ = 0;  // as the runner: a trial's attempts count from 0 in each run

  // Resume at the first trial not completed, as the runner does; trials completed after a
  // gap are skipped when their turn comes (never run again).
  completed_ = 0;
  for (const session::TrialRecord& t : trials_) completed_ += t.status == session::TrialStatus::kCompleted ? 1 : 0;
  next_ = 0;
  skipCompleted();
  if (next_ >= trials_.size()) {
    state_ = State::kFinished;
  } else if (next_ > 0) {
    state_ = State::kResting;  // resuming: the runner rests before the first trial too
    rest_until_s_ = now_s + db_.study().protocol.rest_s;
  } else {
    state_ = State::kReady;
  }
}

std::string StudySession::participantKind() const {
  for (const session::SubjectRecord& s : db_.subjects()) {
    if (s.id == subject_) return s.spec.participant;
  }
  return {};
}

void StudySession::tick(double now_s) {
  if (state_ == State::kResting && now_s >= rest_until_s_) state_ = State::kReady;
}

void StudySession::skipRest() {
  if (state_ == State::kResting) state_ = State::kReady;
}

double StudySession::restRemaining_s(double now_s) const noexcept {
  return state_ == State::kResting ? std::max(0.0, rest_until_s_ - now_s) : 0.0;
}

const session::TrialRecord* StudySession::currentTrial() const noexcept {
  return next_ < trials_.size() && state_ != State::kNoSubject ? &trials_[next_] : nullptr;
}

std::string StudySession::prompt() const {
  const session::TrialRecord* record = currentTrial();
  if (record == nullptr) return state_ == State::kFinished ? "Every trial is done. Thank you!" : "";
  const session::TrialPlan& plan = record->plan;
  const session::Protocol& protocol = db_.study().protocol;
  return fmt::format("{} with {}: trial {} of {}", plan.phase == session::Phase::kTraining ? "Training" : "Recall",
                     guidance::modeName(plan.mode), plan.index,
                     plan.phase == session::Phase::kTraining ? protocol.training_trials : protocol.recall_trials);
}

session::TrialSetup StudySession::currentSetup() const {
  const session::TrialRecord* record = currentTrial();
  HATTR_DEMAND(record != nullptr, "no current trial for subject {}", subject_);
  // StudyRunner's set-up, in real time for a person.
  session::TrialSetup setup = session::studyTrialSetup(db_.study(), record->plan, reference_);
  setup.clock = session::Clock::kRealTime;
  setup.live_guidance = mentor_.get();
  for (const session::SubjectRecord& s : db_.subjects()) {
    if (s.id == subject_) setup.live_seed = session::studyLiveSeed(s.spec, record->plan, repeats_);
  }
  return setup;
}

void StudySession::beginTrial() {
  HATTR_DEMAND(state_ == State::kReady || state_ == State::kResting, "study: beginTrial() in state {}",
               stateName(state_));
  const session::TrialRecord* record = currentTrial();
  HATTR_DEMAND(record != nullptr, "study: no trial to begin");
  if (!session_id_) session_id_ = db_.beginSession(subject_);
  db_.markRunning(record->id, *session_id_);
  state_ = State::kRunning;
}

std::string StudySession::completeTrial(session::TrialResult result, double now_s) {
  HATTR_DEMAND(state_ == State::kRunning, "study: completeTrial() in state {}", stateName(state_));
  if (result.profile.empty()) {
    state_ = State::kReady;
    throw Error("the trial recorded no samples; it stays to be run again");
  }
  // Nothing in the profile may depend on when it ran (the runner's rule).
  result.profile.metadata().created_utc = "";
  const session::TrialRecord& record = trials_[next_];
  const std::string disturbed = session::noteLoopCounters(result);
  try {
    if (session::repeatDisturbedTrial(db_.study().protocol, disturbed, repeats_)) {
      db_.keepDisturbedAttempt(record.id, result.profile, disturbed);
      ++repeats_;
      state_ = State::kReady;  // the same trial again
      return disturbed;
    }
    db_.completeTrial(record.id, result.profile,
                      fmt::format("ok: {} samples, {} missed, {} faults{}", result.profile.size(), result.missed_samples,
                                  result.faults, disturbed.empty() ? "" : "; disturbed"),
                      disturbed);
  } catch (...) {
    state_ = State::kReady;  // not stored: the trial stays running in the database, to be run again
    throw;
  }
  repeats_ = 0;
  trials_[next_].status = session::TrialStatus::kCompleted;
  ++completed_;
  ++next_;
  skipCompleted();
  if (next_ >= trials_.size()) {
    state_ = State::kFinished;
    db_.endSession(*session_id_);
    session_id_.reset();
  } else {
    state_ = State::kResting;
    rest_until_s_ = now_s + db_.study().protocol.rest_s;
  }
  return disturbed;
}

void StudySession::failTrial(const std::string& reason) {
  HATTR_DEMAND(state_ == State::kRunning, "study: failTrial() in state {}", stateName(state_));
  db_.failTrial(trials_[next_].id, reason);
  repeats_ = 0;  // the runner stops at a failed trial; its next run starts the trial at attempt 0
  state_ = State::kReady;
}

void StudySession::skipCompleted() {
  while (next_ < trials_.size() && trials_[next_].status == session::TrialStatus::kCompleted) ++next_;
}

void StudySession::abandonTrial() {
  if (state_ == State::kRunning) state_ = State::kReady;
}

std::string_view stateName(StudySession::State state) {
  switch (state) {
    case StudySession::State::kNoSubject: return "no subject";
    case StudySession::State::kResting: return "resting";
    case StudySession::State::kReady: return "ready";
    case StudySession::State::kRunning: return "running";
    case StudySession::State::kFinished: return "finished";
  }
  return "?";
}

}  // namespace hattr::studio
