#include "core/study_session.hpp"

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/net/study_mentor.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/study_schedule.hpp"

namespace hattr::studio {

StudySession::StudySession(const std::filesystem::path& file)
    : db_(session::StudyDatabase::open(file, session::OpenMode::kRunner)) {
  // The expert, the environment and the reference, as StudyRunner builds them.
  const session::StudyDefinition& study = db_.study();
  for (const auto& [skill, path] : study.experts) experts_.emplace(skill, db_.expert(skill));
  const render::WorldConfig world = render::parseWorldConfig(study.world.dump(), "study world");
  environment_ = std::make_unique<session::TrialEnvironment>(study.device, world, study.rate_hz);
  references_ = session::studyReferences(db_);
  // The expert's station for the mentored modes' training trials, as `hattr study run`'s.
  if (study.hasMentoredModes()) {
    mentor_ = net::makeStudyMentor(study.mentor, experts_.at(study.skill), world, study.rate_hz);
  }
}

const HapticProfile& StudySession::expert() const {
  const session::TrialRecord* trial = currentTrial();
  return experts_.at(trial != nullptr ? trial->plan.skill : db_.study().skill);
}

const std::shared_ptr<const guidance::ReferenceTrajectory>& StudySession::reference() const {
  const session::TrialRecord* trial = currentTrial();
  return references_.at(trial != nullptr ? trial->plan.skill : db_.study().skill);
}

StudySession::~StudySession() {
  try {
    if (session_id_) db_.endSession(*session_id_);
  } catch (...) {  // closing must not throw; the session's end time stays empty
  }
}

void StudySession::selectSubject(const std::string& subject_id, double now_s) {
  HATTR_THROW_UNLESS(state_ != State::kRunning, "study: cannot change subject while a trial runs");
  std::optional<session::SubjectRecord> record;
  for (const session::SubjectRecord& s : db_.subjects()) {
    if (s.id == subject_id) record = s;
  }
  HATTR_THROW_UNLESS(record.has_value(), "study {}: no subject \"{}\"", db_.file().string(), subject_id);
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
  trials_.emplace(db_.study(), *record, db_.trials(subject_id), references_);
  // Resume at the first trial not completed; trials completed after a gap are passed when
  // their turn comes (never run again). A rest comes first unless this is the first trial.
  (void)trials_->passCompleted();
  if (trials_->current() == nullptr) {
    state_ = State::kFinished;
  } else if (trials_->restBefore()) {
    state_ = State::kResting;
    rest_until_s_ = now_s + trials_->restSeconds();
  } else {
    state_ = stateBeforeSession();
  }
}

StudySession::State StudySession::stateBeforeSession() const {
  // The subject's first trial, or a session already begun (resumed): ready.
  if (trials_->position() == 0) return State::kReady;
  return schedule().timing == session::SubjectSchedule::Timing::kInProgress ? State::kReady : State::kNextSession;
}

session::SubjectSchedule StudySession::schedule(const std::string& subject_id) const {
  const std::string& who = subject_id.empty() ? subject_ : subject_id;
  return session::subjectSchedule(db_.study(), db_.trials(who), session::localToday());
}

void StudySession::beginNextSession() {
  HATTR_DEMAND(state_ == State::kNextSession, "study: beginNextSession() in state {}", stateName(state_));
  state_ = State::kReady;
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
  return trials_ && state_ != State::kNoSubject ? trials_->current() : nullptr;
}

std::string StudySession::prompt(session::SubjectTrials::Wording wording) const {
  if (currentTrial() == nullptr) return state_ == State::kFinished ? "Every trial is done. Thank you!" : "";
  if (state_ == State::kNextSession) {
    std::string next = session::scheduleText(schedule());
    if (next.starts_with("next: ")) next.erase(0, 6);
    return fmt::format("Next session for {}: {}", subject_, next);
  }
  return trials_->prompt(wording);
}

session::TrialSetup StudySession::currentSetup() const {
  HATTR_DEMAND(currentTrial() != nullptr, "no current trial for subject {}", subject_);
  return trials_->setup(session::Clock::kRealTime, mentor_.get());  // in real time, for a person
}

void StudySession::beginTrial() {
  HATTR_DEMAND(state_ == State::kReady || state_ == State::kResting, "study: beginTrial() in state {}",
               stateName(state_));
  HATTR_DEMAND(currentTrial() != nullptr, "study: no trial to begin");
  if (!session_id_) session_id_ = db_.beginSession(subject_);
  trials_->begin(db_, *session_id_);
  state_ = State::kRunning;
}

std::string StudySession::completeTrial(session::TrialResult result, double now_s) {
  HATTR_DEMAND(state_ == State::kRunning, "study: completeTrial() in state {}", stateName(state_));
  HATTR_DEMAND(result.failure.empty(), "study: a failed trial goes to failTrial()");
  session::SubjectTrials::Outcome outcome;
  try {
    outcome = trials_->end(db_, result, {});
  } catch (...) {
    state_ = State::kReady;  // not stored: the trial stays running in the database, to be run again
    throw;
  }
  if (outcome.ending != session::SubjectTrials::Ending::kStored) {
    state_ = State::kReady;  // disturbed: the same trial again
    return outcome.disturbed;
  }
  // Stored: a rest before the next trial, or the subject is done (the session ends).
  (void)trials_->passCompleted();
  if (trials_->current() == nullptr) {
    state_ = State::kFinished;
    db_.endSession(*session_id_);
    session_id_.reset();
  } else if (trials_->restBefore()) {
    state_ = State::kResting;
    rest_until_s_ = now_s + trials_->restSeconds();
  } else {
    // A session of the schedule ended: the next is begun when the person is there for it.
    state_ = State::kNextSession;
    db_.endSession(*session_id_);
    session_id_.reset();
  }
  return outcome.disturbed;
}

void StudySession::failTrial(const std::string& reason) {
  HATTR_DEMAND(state_ == State::kRunning, "study: failTrial() in state {}", stateName(state_));
  trials_->fail(db_, reason);
  state_ = State::kReady;
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
    case StudySession::State::kNextSession: return "between sessions";
    case StudySession::State::kFinished: return "finished";
  }
  return "?";
}

}  // namespace hattr::studio
