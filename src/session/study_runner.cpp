#include "hattr/session/study_runner.hpp"

#include <algorithm>
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

std::string noteLoopCounters(TrialResult& result) {
  const std::string disturbed = disturbanceOf(result);
  auto& extra = result.profile.metadata().extra;
  extra["loop_ticks"] = fmt::format("{}", result.ticks);
  extra["loop_overruns"] = fmt::format("{}", result.overruns);
  extra["loop_stalls"] = fmt::format("{}", result.stalls);
  extra["missed_samples"] = fmt::format("{}", result.missed_samples);
  extra["safety_faults"] = fmt::format("{}", result.faults);
  extra["device_link_faults"] = fmt::format("{}", result.link_faults);
  if (result.mentor_link_faults > 0) extra["mentor_link_faults"] = fmt::format("{}", result.mentor_link_faults);
  if (!disturbed.empty()) extra["disturbed"] = disturbed;
  return disturbed;
}

std::uint64_t studyLiveSeed(const SubjectSpec& subject, const TrialPlan& plan, int attempt) {
  return subject.seed * 1'000'003ULL + static_cast<std::uint64_t>(plan.sequence) * 31ULL +
         static_cast<std::uint64_t>(attempt);
}

TrialSetup studyTrialSetup(const StudyDefinition& study, const TrialPlan& plan,
                           std::shared_ptr<const guidance::ReferenceTrajectory> reference) {
  HATTR_THROW_UNLESS(reference != nullptr, "study \"{}\", subject {}, trial {}: expected the expert's reference "
                     "trajectory, got none", study.name, plan.subject, plan.sequence);
  // The mode's guidance in training, none (BASIC) in recall.
  TrialSetup setup;
  setup.guidance.mode = plan.view.guidance ? plan.mode : guidance::TrainingMode::kBasic;
  setup.guidance.playback.indexing = study.indexing;
  // The trial ends when the subject is done (pen up long enough) or at the maximum; an old
  // study file without trial_end keeps its fixed window.
  if (study.protocol.fixed_window) {
    setup.duration_s = reference->duration_s() + study.protocol.tail_s;
  } else {
    setup.duration_s = study.protocol.trial_end.maxDuration_s(reference->duration_s());
    setup.pen_up_end_s = study.protocol.trial_end.pen_up_s;
  }
  setup.reference = std::move(reference);
  setup.metadata.subject = plan.subject;
  setup.metadata.skill = study.skill;
  setup.metadata.source = fmt::format("study:{}", study.name);
  setup.metadata.extra["study_mode"] = std::string(guidance::modeName(plan.mode));
  setup.metadata.extra["phase"] = std::string(phaseName(plan.phase));
  setup.metadata.extra["trial"] = fmt::format("{}", plan.index);
  setup.metadata.extra["sequence"] = fmt::format("{}", plan.sequence);
  setup.metadata.extra["reference_shown"] = plan.view.show_reference ? "yes" : "no";
  return setup;
}

bool repeatDisturbedTrial(const Protocol& protocol, const std::string& disturbed, int repeats_so_far) {
  return !disturbed.empty() && protocol.disturbed == DisturbedPolicy::kRepeat && repeats_so_far < protocol.max_repeats;
}

std::string disturbanceOf(const TrialResult& r) {
  std::vector<std::string> parts;
  const auto add = [&parts](std::uint64_t n, const char* one, const char* many) {
    if (n > 0) parts.push_back(fmt::format("{} {}", n, n == 1 ? one : many));
  };
  add(r.stalls, "stall (force zeroed)", "stalls (force zeroed)");
  add(r.missed_samples, "missed sample", "missed samples");
  add(r.faults, "safety fault", "safety faults");
  add(r.link_faults, "lost device link", "lost device links");
  add(r.mentor_link_faults, "lost link to the mentor", "lost links to the mentor");
  std::string text;
  for (const auto& p : parts) text += (text.empty() ? "" : " · ") + p;
  return text;
}

std::unique_ptr<Participant> makeScriptParticipant(const SubjectRecord& subject, const HapticProfile& expert) {
  const auto& options = subject.spec.options;
  HapticProfile script = options.contains("hand") ? io::readProfileCsv(options["hand"].get<std::string>()) : expert;
  const double jitter_mm = options.value("jitter_mm", 0.0);
  HATTR_THROW_UNLESS(jitter_mm >= 0.0 && jitter_mm <= 50.0, "subject {}: options.jitter_mm: expected 0 to 50, got {}",
                     subject.id, jitter_mm);
  return std::make_unique<ScriptParticipant>(std::move(script), jitter_mm / 1000.0, subject.spec.seed);
}

StudyRunner::StudyRunner(StudyDatabase& db, ParticipantFactory factory) : db_(db), factory_(std::move(factory)) {
  const StudyDefinition& study = db_.study();
  expert_ = db_.expert(study.skill);
  world_ = render::parseWorldConfig(study.world.dump(), "study world");
  reference_ = std::make_shared<guidance::ReferenceTrajectory>(expert_, study.rate_hz);
}

int StudyRunner::run(const RunOptions& options) {
  HATTR_THROW_UNLESS(options.mentor != nullptr || !db_.study().hasMentoredModes(),
                     "study \"{}\" has mentored modes: their training trials need the expert's station (the study "
                     "file's mentor block), which this app did not provide", db_.study().name);
  HATTR_THROW_UNLESS(options.subjects_at_once >= 1, "subjects at once: expected at least 1, got {}",
                     options.subjects_at_once);
  stopping_ = false;
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
    const int budget = options.max_trials < 0 ? -1 : options.max_trials - ran;
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

// Every use of the database goes through withDatabase: other subjects may run beside this one.
int StudyRunner::runSubject(const SubjectRecord& subject, const RunOptions& options, int budget,
                            EnvironmentSlot& environment) {
  const StudyDefinition& study = db_.study();
  const auto profileOf = [this](std::int64_t id) { return withDatabase([id](StudyDatabase& db) { return db.trialProfile(id); }); };
  std::vector<TrialRecord> trials = withDatabase([&](StudyDatabase& db) { return db.trials(subject.id); });
  // A finished subject costs nothing: no participant is made and nothing is relived.
  const auto left = std::count_if(trials.begin(), trials.end(),
                                  [](const TrialRecord& t) { return t.status != TrialStatus::kCompleted; });
  if (left == 0) return 0;
  if (stopping_) return 0;  // another subject's trial failed meanwhile
  const auto participant = factory_(subject, expert_);

  // Resume: the participant relives the trials already done, in order.
  int completed = 0;
  for (const TrialRecord& t : trials) {
    if (t.status != TrialStatus::kCompleted) break;
    participant->trialCompleted(t.plan, profileOf(t.id));
    ++completed;
  }

  const std::int64_t session = withDatabase([&](StudyDatabase& db) { return db.beginSession(subject.id); });
  int ran = 0;
  for (std::size_t i = static_cast<std::size_t>(completed); i < trials.size(); ++i) {
    if ((budget >= 0 && ran >= budget) || stopping_) break;
    const TrialRecord& record = trials[i];
    const TrialPlan& plan = record.plan;
    // A trial completed after a gap (an earlier one left pending) is never run again: the
    // participant relives it in its place, as on resume.
    if (record.status == TrialStatus::kCompleted) {
      participant->trialCompleted(plan, profileOf(record.id));
      continue;
    }
    if (i > static_cast<std::size_t>(completed) || completed > 0) participant->rest(study.protocol.rest_s);
    participant->prompt(fmt::format("{} with {}: trial {} of {}", plan.phase == Phase::kTraining ? "Training" : "Recall",
                                    guidance::modeName(plan.mode), plan.index,
                                    plan.phase == Phase::kTraining ? study.protocol.training_trials
                                                                   : study.protocol.recall_trials));

    // The trial, set up as every app sets up a study trial; the runner's clock.
    TrialSetup setup = studyTrialSetup(study, plan, reference_);
    setup.clock = options.clock;
    setup.live_guidance = options.mentor;

    // The trial; a disturbed one is kept and run again while the policy says so.
    TrialResult result;
    std::string disturbed;
    for (int attempt = 0;; ++attempt) {
      setup.inject_stall_at_s = options.inject_stall_at_s
                                    ? withDatabase([&](StudyDatabase&) { return options.inject_stall_at_s(plan, attempt); })
                                    : -1.0;
      setup.live_seed = studyLiveSeed(subject.spec, plan, attempt);
      withDatabase([&](StudyDatabase& db) { db.markRunning(record.id, session); });
      if (!environment) environment = std::make_unique<TrialEnvironment>(study.device, world_, study.rate_hz);
      result = runTrial(*environment, setup, participant->handForTrial(plan));
      // A trial the device broke off is not data: mark it, keep everything stored, and stop.
      if (!result.failure.empty()) {
        withDatabase([&](StudyDatabase& db) {
          db.failTrial(record.id, result.failure);
          db.endSession(session);
        });
        throw Error(fmt::format("subject {}: {} trial {} with {} failed: {}; completed trials are kept, and `study "
                                "run` repeats this one",
                                subject.id, phaseName(plan.phase), plan.index, guidance::modeName(plan.mode),
                                result.failure));
      }
      // Nothing in the profile may depend on when it ran, so a resumed study is bit-identical.
      result.profile.metadata().created_utc = "";
      disturbed = noteLoopCounters(result);
      if (!repeatDisturbedTrial(study.protocol, disturbed, attempt)) break;
      withDatabase([&](StudyDatabase& db) { db.keepDisturbedAttempt(record.id, result.profile, disturbed); });
      participant->prompt(fmt::format("That trial was disturbed ({}): once more", disturbed));
    }
    const std::string outcome = fmt::format("ok: {} samples, {} missed, {} faults{}", result.profile.size(),
                                            result.missed_samples, result.faults, disturbed.empty() ? "" : "; disturbed");
    withDatabase([&](StudyDatabase& db) { db.completeTrial(record.id, result.profile, outcome, disturbed); });
    // The participant learns from what was stored (at a declared resolution, not what was
    // measured), as it does on resume: a resumed study stays bit-identical.
    participant->trialCompleted(plan, study.resolution.empty() ? result.profile : profileOf(record.id));
    if (study.protocol.show_scores && options.score_text) {
      participant->prompt(withDatabase([&](StudyDatabase&) { return options.score_text(plan, result.profile); }));
    }
    ++ran;
    if (options.progress) {
      TrialRecord done = record;
      done.status = TrialStatus::kCompleted;
      withDatabase([&](StudyDatabase&) {  // one progress call at a time
        options.progress({subject.id, static_cast<int>(i) + 1, static_cast<int>(trials.size()), &done});
      });
    }
  }
  withDatabase([&](StudyDatabase& db) { db.endSession(session); });
  return ran;
}

}  // namespace hattr::session
