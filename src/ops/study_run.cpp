#include "hattr/ops/study_run.hpp"

#include <algorithm>
#include <memory>

#include "hattr/net/study_mentor.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/sim/participant.hpp"

namespace hattr::ops {
namespace {

/// The unfinished trials of the subjects a run does, at most max_trials.
int trialsToRun(const session::StudyDatabase& db, const StudyRunOptions& o) {
  int left = 0;
  for (const session::TrialRecord& t : db.trials()) {
    const bool selected = o.subject.empty() || t.plan.subject == o.subject;
    left += selected && t.status != session::TrialStatus::kCompleted ? 1 : 0;
  }
  return o.max_trials >= 0 ? std::min(left, o.max_trials) : left;
}

}  // namespace

nlohmann::json scheduleJson(const session::SubjectSchedule& s) {
  return {{"timing", std::string(session::timingName(s.timing))},
          {"session", s.session + 1},
          {"sessions", s.sessions},
          {"day", s.day},
          {"due", s.due ? nlohmann::json(s.due->iso()) : nlohmann::json(nullptr)},
          {"days_off", s.days_off},
          {"text", session::scheduleText(s)}};
}

nlohmann::json StudyRunResult::toJson() const {
  nlohmann::json left = nlohmann::json::array();
  for (const auto& w : waiting) left.push_back({{"subject", w.subject}, {"schedule", scheduleJson(w.schedule)}});
  return {{"trials_to_run", trials_to_run}, {"trials_run", trials_run}, {"waiting", left}};
}

StudyRunResult runStudy(const StudyRunOptions& options) {
  session::StudyDatabase db = session::StudyDatabase::open(options.db, session::OpenMode::kRunner,
                                                           {.lease_timeout_s = options.lease_timeout_s});
  const session::StudyDefinition& study = db.study();
  const std::string device_uri = study.device;
  session::StudyRunner runner(db, [&device_uri](const session::SubjectRecord& s, const HapticProfile& expert) {
    return sim::makeUnattendedParticipant(s, expert, device_uri);
  });
  session::RunOptions run{.only_subject = options.subject,
                          .clock = options.clock,
                          .progress = options.progress,
                          .max_trials = options.max_trials,
                          .subjects_at_once = options.subjects_at_once,
                          .follow_calendar = options.follow_calendar};
  // The expert's station for the mentored modes' training trials (the study file's mentor).
  std::unique_ptr<session::LiveGuidance> mentor;
  if (study.hasMentoredModes()) {
    mentor = net::makeStudyMentor(study.mentor, db.expert(study.skill),
                                  render::parseWorldConfig(study.world.dump(), "study world"), study.rate_hz);
    run.mentor = mentor.get();
  }
  StudyRunResult result;
  result.trials_to_run = trialsToRun(db, options);
  if (options.started) options.started(result.trials_to_run);
  result.trials_run = runner.run(run);
  result.waiting = runner.waiting();
  return result;
}

}  // namespace hattr::ops
