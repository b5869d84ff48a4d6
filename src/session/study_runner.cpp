#include "hattr/session/study_runner.hpp"

#include <algorithm>
#include <chrono>
#include <random>
#include <thread>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_export.hpp"

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

namespace {

/// The rescue folder of a run: the option, or beside a study file, or ./hattr-unstored.
std::filesystem::path rescueFolder(const StudyDatabase& db, const RunOptions& options) {
  if (!options.rescue_folder.empty()) return options.rescue_folder;
  if (db.onPostgres()) return std::filesystem::current_path() / "hattr-unstored";
  return std::filesystem::path(db.file().string() + ".unstored");
}

/// Writes a recording the store refused into `folder`, under its export name (a name already
/// there gets -2, -3...); returns where.
std::filesystem::path rescueRecording(const std::filesystem::path& folder, const TrialPlan& plan,
                                      const HapticProfile& profile) {
  const std::filesystem::path base = folder / trialFileName(plan);
  std::filesystem::create_directories(base.parent_path());
  std::filesystem::path file = base;
  for (int n = 2; std::filesystem::exists(file); ++n) {
    file = base.parent_path() / fmt::format("{}-{}{}", base.stem().string(), n, base.extension().string());
  }
  io::writeProfileCsv(profile, file);
  return file;
}

}  // namespace

void StudyRunner::storeOrRescue(const TrialRecord& record, const HapticProfile& profile, const std::string& outcome,
                                const std::string& disturbed, const RunOptions& options) {
  try {
    withDatabase([&](StudyDatabase& db) { db.completeTrial(record.id, profile, outcome, disturbed); });
  } catch (const SubjectTakenOver&) {
    throw;  // another station runs this subject now: its trial, not this one's
  } catch (const Error& e) {
    // The store refused the trial: its recording is kept in a file, never lost.
    std::filesystem::path file;
    try {
      file = rescueRecording(rescueFolder(db_, options), record.plan, profile);
    } catch (const std::exception& also) {
      throw Error(fmt::format("{}; and the recording could not be kept in a file either: {}", e.what(), also.what()));
    }
    const TrialPlan& plan = record.plan;
    throw Error(fmt::format("{}; subject {}'s {} {} trial {} (sequence {}) was not stored: its recording is kept in {} "
                            "(a profile CSV), and the trial runs again when the study resumes",
                            e.what(), plan.subject, guidance::modeName(plan.mode), phaseName(plan.phase), plan.index,
                            plan.sequence, file.string()));
  }
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
  const auto participant = factory_(subject, expert_);

  // Resume: the participant relives the trials already done, in order.
  int completed = 0;
  for (const TrialRecord& t : trials) {
    if (t.status != TrialStatus::kCompleted) break;
    participant->trialCompleted(t.plan, storedProfile(t.id));
    ++completed;
  }

  const std::int64_t session = withDatabase([&](StudyDatabase& db) { return db.beginSession(subject.id); });
  int ran = 0;
  try {
    runTrialsLeft(subject, options, budget, environment, trials, completed, *participant, session, ran);
  } catch (const SubjectTakenOver&) {
    // Another station took the subject over (this one's lease lapsed): it runs the rest.
    held_elsewhere_ = true;
    withDatabase([&](StudyDatabase& db) { db.endSession(session); });
    return ran;
  }
  withDatabase([&](StudyDatabase& db) { db.endSession(session); });
  return ran;
}

void StudyRunner::runTrialsLeft(const SubjectRecord& subject, const RunOptions& options, int budget,
                                EnvironmentSlot& environment, const std::vector<TrialRecord>& trials, int completed,
                                Participant& participant, std::int64_t session, int& ran) {
  const StudyDefinition& study = db_.study();
  for (std::size_t i = static_cast<std::size_t>(completed); i < trials.size(); ++i) {
    if ((budget >= 0 && ran >= budget) || stopping_) break;
    const TrialRecord& record = trials[i];
    const TrialPlan& plan = record.plan;
    // A trial completed after a gap (an earlier one left pending) is never run again: the
    // participant relives it in its place, as on resume.
    if (record.status == TrialStatus::kCompleted) {
      participant.trialCompleted(plan, storedProfile(record.id));
      continue;
    }
    if (i > static_cast<std::size_t>(completed) || completed > 0) participant.rest(study.protocol.rest_s);
    participant.prompt(fmt::format("{} with {}: trial {} of {}", plan.phase == Phase::kTraining ? "Training" : "Recall",
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
      result = runTrial(*environment, setup, participant.handForTrial(plan));
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
      participant.prompt(fmt::format("That trial was disturbed ({}): once more", disturbed));
    }
    const std::string outcome = fmt::format("ok: {} samples, {} missed, {} faults{}", result.profile.size(),
                                            result.missed_samples, result.faults, disturbed.empty() ? "" : "; disturbed");
    storeOrRescue(record, result.profile, outcome, disturbed, options);
    // The participant learns from what was stored (at a declared resolution, not what was
    // measured), as it does on resume: a resumed study stays bit-identical.
    participant.trialCompleted(plan, study.resolution.empty() ? result.profile : storedProfile(record.id));
    if (study.protocol.show_scores && options.score_text) {
      participant.prompt(withDatabase([&](StudyDatabase&) { return options.score_text(plan, result.profile); }));
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
}

}  // namespace hattr::session
