#include "hattr/session/subject_trials.hpp"

#include <algorithm>
#include <charconv>

#include <fmt/format.h>

#include "hattr/analysis/kinematics.hpp"
#include "hattr/core/error.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/guidance/strategy_schedule.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_export.hpp"

namespace hattr::session {

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
  setup.metadata.skill = plan.skill;
  setup.metadata.source = fmt::format("study:{}", study.name);
  setup.metadata.extra["study_mode"] = std::string(guidance::modeName(plan.mode));
  setup.metadata.extra["phase"] = plan.phase;
  setup.metadata.extra["trial"] = fmt::format("{}", plan.index);
  setup.metadata.extra["sequence"] = fmt::format("{}", plan.sequence);
  setup.metadata.extra["reference_shown"] = plan.view.show_reference ? "yes" : "no";
  // The study's strategy parameters, every strategy's (a scheduled one plays its base law's).
  for (const auto& [mode, settings] : study.strategy_parameters) {
    guidance::setStrategyParameters(setup.guidance, mode, settings);
  }
  if (!study.paper_form) {  // the paper's trials keep their metadata as it always was
    setup.metadata.extra["group"] = plan.group;
    setup.metadata.extra["session"] = fmt::format("{}", plan.session + 1);
    setup.metadata.extra["day"] = fmt::format("{}", plan.day);
    setup.metadata.extra["block"] = fmt::format("{}", plan.block + 1);
  }
  return setup;
}

StudyReferences studyReferences(const StudyDatabase& db) {
  StudyReferences references;
  for (const auto& [skill, file] : db.study().experts) {
    references[skill] = std::make_shared<guidance::ReferenceTrajectory>(db.expert(skill), db.study().rate_hz);
  }
  return references;
}


bool repeatDisturbedTrial(const Protocol& protocol, const std::string& disturbed, int repeats_so_far) {
  return !disturbed.empty() && protocol.disturbed == DisturbedPolicy::kRepeat && repeats_so_far < protocol.max_repeats;
}

namespace {

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

std::filesystem::path defaultRescueFolder(const StudyDatabase& db) {
  if (db.onPostgres()) return std::filesystem::current_path() / "hattr-unstored";
  return std::filesystem::path(db.file().string() + ".unstored");
}

SubjectTrials::SubjectTrials(const StudyDefinition& study, SubjectRecord subject, std::vector<TrialRecord> trials,
                             StudyReferences references)
    : study_(study), subject_(std::move(subject)), trials_(std::move(trials)), references_(std::move(references)) {
  completed_ = static_cast<int>(std::count_if(trials_.begin(), trials_.end(), [](const TrialRecord& t) {
    return t.status == TrialStatus::kCompleted;
  }));
}

std::vector<TrialRecord> SubjectTrials::passCompleted() {
  std::vector<TrialRecord> passed;
  for (; next_ < trials_.size() && trials_[next_].status == TrialStatus::kCompleted; ++next_) {
    passed.push_back(trials_[next_]);
  }
  return passed;
}

const TrialRecord* SubjectTrials::current() const noexcept {
  return next_ < trials_.size() ? &trials_[next_] : nullptr;
}

bool SubjectTrials::restBefore() const noexcept {
  return next_ > 0 && next_ < trials_.size() && trials_[next_].plan.session == trials_[next_ - 1].plan.session;
}

double SubjectTrials::restSeconds() const {
  HATTR_DEMAND(current() != nullptr, "subject {}: no trial left to rest before", subject_.id);
  return blockOf(study_, current()->plan).rest_s;
}

int SubjectTrials::daysBefore() const noexcept {
  if (next_ == 0 || next_ >= trials_.size()) return 0;
  return trials_[next_].plan.day - trials_[next_ - 1].plan.day;
}

namespace {

/// A phase as a learner reads it (SubjectTrials::Wording::kPlain); other phases as they are.
std::string plainPhase(const std::string& phase) {
  if (phase == kPhaseBaseline) return "before practice";
  if (phase == kPhasePostTest) return "written alone";
  if (phase == kPhaseRetention) return "written alone, days later";
  if (phase == kPhaseTransfer) return "a new letter";
  return phase;
}

}  // namespace

std::string SubjectTrials::prompt(Wording wording) const {
  HATTR_DEMAND(current() != nullptr, "subject {}: no trial left to prompt for", subject_.id);
  const TrialPlan& plan = current()->plan;
  const bool plain = wording == Wording::kPlain;
  std::string phase = plain ? plainPhase(plan.phase) : plan.phase;
  if (!phase.empty() && phase[0] >= 'a' && phase[0] <= 'z') phase[0] = static_cast<char>(phase[0] - 'a' + 'A');
  // The strategy is named where its force acts, and in the paper's recall (the mode's block).
  const bool named = plan.view.guidance || study_.paper_form;
  const std::string_view strategy = plain ? guidance::strategyInfo(plan.mode).plain_name : guidance::modeName(plan.mode);
  return fmt::format("{}{}: trial {} of {}", phase, named ? fmt::format(" with {}", strategy) : "", plan.index,
                     blockOf(study_, plan).trials);
}

TrialSetup SubjectTrials::setup(Clock clock, LiveGuidance* mentor) const {
  HATTR_DEMAND(current() != nullptr, "subject {}: no trial left to set up", subject_.id);
  const auto reference = references_.find(current()->plan.skill);
  HATTR_DEMAND(reference != references_.end(), "subject {}: no expert reference for skill {}", subject_.id,
               current()->plan.skill);
  TrialSetup setup = studyTrialSetup(study_, current()->plan, reference->second);
  setup.clock = clock;
  setup.live_guidance = mentor;
  setup.live_seed = studyLiveSeed(subject_.spec, current()->plan, attempt_);
  setup.guidance.noise.seed = setup.live_seed;  // NOISE: the same trial and attempt, the same force
  // A scheduled strategy's law and gain, from the tracking errors stored with the trials before.
  const TrialPlan& plan = current()->plan;
  if (guidance::isScheduled(plan.mode) && plan.view.guidance) {
    setup.guidance.scheduled = guidance::scheduleTrial(setup.guidance, plan.mode, scheduledErrorsBefore());
  }
  return setup;
}

bool SubjectTrials::scheduledTrial(const TrialPlan& plan) noexcept {
  return guidance::isScheduled(plan.mode) && plan.view.guidance;
}

std::vector<double> SubjectTrials::scheduledErrorsBefore() const {
  const TrialPlan& now = current()->plan;
  std::vector<double> errors;
  for (std::size_t i = 0; i < next_; ++i) {
    const TrialRecord& before = trials_[i];
    if (before.status != TrialStatus::kCompleted || before.plan.mode != now.mode || !scheduledTrial(before.plan)) continue;
    const auto it = before.strategy_state.find("tracking_rms_m");
    double error = 0.0;
    const bool stored = it != before.strategy_state.end() &&
                        std::from_chars(it->second.data(), it->second.data() + it->second.size(), error).ec == std::errc();
    HATTR_THROW_UNLESS(stored, "subject {}: trial {} ({} training, sequence {}) has no stored tracking error "
                       "(tracking_rms_m), which {} schedules the next trial from", subject_.id, before.plan.index,
                       guidance::modeName(before.plan.mode), before.plan.sequence, guidance::modeName(now.mode));
    errors.push_back(error);
  }
  return errors;
}

void SubjectTrials::begin(StudyDatabase& db, std::int64_t session) const {
  HATTR_DEMAND(current() != nullptr, "subject {}: no trial left to begin", subject_.id);
  db.markRunning(current()->id, session);
}

void SubjectTrials::fail(StudyDatabase& db, const std::string& reason) {
  HATTR_DEMAND(current() != nullptr, "subject {}: no trial to fail", subject_.id);
  db.failTrial(current()->id, reason);
  attempt_ = 0;  // a failed trial stops the run; its next run starts at attempt 0
}

SubjectTrials::Outcome SubjectTrials::end(StudyDatabase& db, TrialResult& result,
                                          const std::filesystem::path& rescue_folder) {
  HATTR_DEMAND(current() != nullptr, "subject {}: no trial to end", subject_.id);
  TrialRecord& record = trials_[next_];
  // A trial the device or the mentor broke off is not data.
  if (!result.failure.empty()) {
    fail(db, result.failure);
    return {Ending::kFailed, "", record};
  }
  if (result.profile.empty()) throw Error("the trial recorded no samples; it stays to be run again");
  // Nothing in the profile may depend on when it ran, so a resumed study is bit-identical.
  result.profile.metadata().created_utc = "";
  // A scheduled strategy's trial keeps its tracking error: the next trial's schedule reads it.
  measure(result);
  const auto& extra = result.profile.metadata().extra;
  // Its counters and events in the recording (TrialRun::finish wrote them already; a result
  // built elsewhere gets them here).
  const std::string disturbed = noteLoopCounters(result);
  // A disturbed trial is kept as an attempt and run again while the policy says so.
  if (repeatDisturbedTrial(study_.protocol, disturbed, attempt_)) {
    db.keepDisturbedAttempt(record.id, result.profile, disturbed);
    ++attempt_;
    return {Ending::kRepeat, disturbed, record};
  }
  const std::string outcome = fmt::format("ok: {} samples, {} missed, {} faults{}", result.profile.size(),
                                          result.missed_samples, result.faults, disturbed.empty() ? "" : "; disturbed");
  storeOrRescue(db, record, result.profile, outcome, disturbed, rescue_folder);
  record.status = TrialStatus::kCompleted;
  if (scheduledTrial(record.plan)) {  // as StudyDatabase::trials reads it back
    for (const char* key : {"guidance_law", "guidance_gain", "tracking_rms_m"}) {
      if (const auto it = extra.find(key); it != extra.end()) record.strategy_state[key] = it->second;
    }
  }
  ++completed_;
  ++next_;
  attempt_ = 0;
  return {Ending::kStored, disturbed, record};
}

void SubjectTrials::measure(TrialResult& result) const {
  HATTR_DEMAND(current() != nullptr, "subject {}: no trial to measure", subject_.id);
  const TrialPlan& plan = current()->plan;
  auto& extra = result.profile.metadata().extra;
  if (result.profile.empty()) return;
  // Every trial keeps its handwriting kinematics (docs/analysis.md), each as its shortest exact text.
  if (kinematics_ && !extra.contains(kKinematicsPrefix + std::string("duration_s"))) {
    const nlohmann::json k = analysis::toJson(analysis::trialKinematics(result.profile));
    for (const char* name : analysis::kinematicsNames()) {
      const nlohmann::json& v = k.at(name);
      extra[kKinematicsPrefix + std::string(name)] = v.is_null() ? "NA" : v.dump();
    }
  }
  if (!scheduledTrial(plan) || extra.contains("tracking_rms_m")) return;
  const double error = guidance::trackingErrorRms(*references_.at(plan.skill), result.profile);
  extra["tracking_rms_m"] = fmt::format("{}", error);
}

void SubjectTrials::storeOrRescue(StudyDatabase& db, const TrialRecord& record, const HapticProfile& profile,
                                  const std::string& outcome, const std::string& disturbed,
                                  const std::filesystem::path& rescue_folder) {
  try {
    db.completeTrial(record.id, profile, outcome, disturbed);
  } catch (const SubjectTakenOver&) {
    throw;  // another station runs this subject now: its trial, not this one's
  } catch (const Error& e) {
    // The store refused the trial: its recording is kept in a file, never lost.
    std::filesystem::path file;
    try {
      file = rescueRecording(rescue_folder.empty() ? defaultRescueFolder(db) : rescue_folder, record.plan, profile);
    } catch (const std::exception& also) {
      throw Error(fmt::format("{}; and the recording could not be kept in a file either: {}", e.what(), also.what()));
    }
    const TrialPlan& plan = record.plan;
    throw Error(fmt::format("{}; subject {}'s {} {} trial {} (sequence {}) was not stored: its recording is kept in {} "
                            "(a profile CSV), and the trial runs again when the study resumes",
                            e.what(), plan.subject, guidance::modeName(plan.mode), plan.phase, plan.index,
                            plan.sequence, file.string()));
  }
}

}  // namespace hattr::session
