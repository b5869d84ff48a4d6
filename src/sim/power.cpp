#include "hattr/sim/power.hpp"

#include <algorithm>
#include <array>
#include <iterator>
#include <limits>
#include <numeric>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include <fmt/format.h>

#include "hattr/analysis/anova.hpp"
#include "hattr/analysis/kinematics.hpp"
#include "hattr/analysis/trial_score.hpp"
#include "hattr/core/error.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/in_silico.hpp"
#include "hattr/sim/participant.hpp"

namespace hattr::sim {
namespace {

void checkOptions(const PowerOptions& o) {
  HATTR_THROW_UNLESS(!o.subject_counts.empty(), "subjects: expected at least one number of subjects");
  std::set<int> seen;
  for (const int n : o.subject_counts) {
    HATTR_THROW_UNLESS(n >= 3 && n <= 1000, "subjects: expected 3 to 1000 subjects per design (Tukey's test needs 3), got {}", n);
    HATTR_THROW_UNLESS(seen.insert(n).second, "subjects: {} is given twice", n);
  }
  HATTR_THROW_UNLESS(o.replicates >= 1 && o.replicates <= 1'000'000, "replicates: expected 1 to 1000000, got {}", o.replicates);
  HATTR_THROW_UNLESS(o.alpha > 0.0 && o.alpha < 1.0, "alpha: expected a level in (0, 1), got {}", o.alpha);
  HATTR_THROW_UNLESS(o.threads >= 1 && o.threads <= 256, "threads: expected 1 to 256, got {}", o.threads);
  // Replicate r's subjects are seeded as the in-silico study with seed + r (subject i:
  // (seed + r)·1000 + i): keep that within a study file's seed range.
  HATTR_THROW_UNLESS(o.seed <= 1'000'000'000'000ULL, "seed: expected 0 to 1e12, got {}", o.seed);
  if (!o.hypothesis.empty()) (void)parseHypothesis(o.hypothesis, "hypothesis");
  if (!o.kinematic.empty()) {
    HATTR_THROW_UNLESS(analysis::isKinematicsName(o.kinematic), "kinematic measure: expected one of {}, got \"{}\"",
                       fmt::join(analysis::kinematicsNames(), ", "), o.kinematic);
  }
}

/// A study file's checks: simulated subjects on the simulated pen, nothing live.
void checkStudy(const session::StudyDefinition& study, const std::filesystem::path& file) {
  const std::string where = file.string();
  HATTR_THROW_UNLESS(study.device.rfind("sim://", 0) == 0,
                     "{}: device \"{}\": a power analysis simulates its studies: expected a sim:// device", where,
                     study.device);
  HATTR_THROW_UNLESS(!study.hasMentoredModes(), "{}: mentored modes are not simulated by a power analysis (yet): "
                     "expected modes without a mentor", where);
  for (const auto& s : study.subjects) {
    HATTR_THROW_UNLESS(s.participant == "simulated",
                       "{}: subject {} is a \"{}\" participant: a power analysis replaces the subjects with simulated "
                       "ones and takes their options from the study's: expected simulated subjects",
                       where, s.id, s.participant);
  }
}

/// The phase a design's power analysis compares: `asked`, or its retention, post-test,
/// recall or last phase.
std::string testedPhase(const session::StudyDefinition& study, const std::string& asked) {
  std::vector<std::string> phases;
  for (const auto& session : study.schedule) {
    for (const auto& block : session.blocks) phases.push_back(block.phase);
  }
  const auto has = [&phases](std::string_view p) { return std::find(phases.begin(), phases.end(), p) != phases.end(); };
  if (!asked.empty()) {
    HATTR_THROW_UNLESS(has(asked), "--phase {}: the design has no such phase: expected one of {}", asked,
                       fmt::join(std::set<std::string>(phases.begin(), phases.end()), ", "));
    return asked;
  }
  for (const std::string_view p : {session::kPhaseRetention, session::kPhasePostTest, session::kPhaseRecall}) {
    if (has(p)) return std::string(p);
  }
  return phases.back();
}

/// A replicate's trials scored as they end, so that its store keeps no samples: each trial the
/// analysis reads is prepared at once (its channels on the expert's time steps, a fraction of
/// its recording) and scored with others a DTW batch at a time, exactly as the analysis would
/// score it (same options, z left out: no metric uses it). Called from the subjects' threads.
class ScoredAsTheyEnd {
 public:
  /// Every trial of a design (its analysis reads them all); the paper's analyzed recall trials,
  /// and the others only when a disturbed one may be replaced by one of them (the "exclude"
  /// policy's spares). Scored as `options` says, as the analysis would score them.
  ScoredAsTheyEnd(const session::StudyDatabase& db, bool every_trial, const report::AnalysisOptions& options)
      : every_trial_(every_trial) {
    const session::Protocol& protocol = db.study().protocol;
    if (protocol.disturbed != session::DisturbedPolicy::kExclude) {
      const std::vector<int> analyzed = session::analyzedRecallTrials(protocol);
      analyzed_recall_.insert(analyzed.begin(), analyzed.end());
    }
    const analysis::ScoreOptions score{.normalization = options.normalization, .cost = options.cost,
                                       .band_fraction = options.band_fraction, .score_z = false,
                                       .score_shape = options.analyze_trajectory, .score_force = options.analyze_force};
    for (const auto& [skill, file] : db.study().experts) {
      skills_.try_emplace(skill, analysis::TrialScorer(db.expert(skill), score));
    }
  }

  void add(const session::TrialRecord& trial, const HapticProfile& profile) {
    if (!every_trial_ && trial.plan.phase != session::kPhaseRecall) return;
    if (!every_trial_ && !analyzed_recall_.empty() && !analyzed_recall_.contains(trial.plan.index)) return;
    Skill& skill = skills_.at(trial.plan.skill);
    analysis::PreparedTrial prepared = skill.scorer.prepare(profile);
    Batch full;
    {
      const std::lock_guard lock(mutex_);
      skill.waiting.ids.push_back(trial.id);
      skill.waiting.trials.push_back(std::move(prepared));
      if (skill.waiting.ids.size() < kBatch) return;
      full = std::exchange(skill.waiting, {});
    }
    score(skill, full);
  }

  /// Every trial's score, the last partial batches scored now.
  std::map<std::int64_t, analysis::TrialScore> finish() {
    for (auto& [name, skill] : skills_) score(skill, std::exchange(skill.waiting, {}));
    return std::move(scores_);
  }

 private:
  // Whole SIMD blocks of the batch kernel (32 trials on any target): no idle lanes.
  static constexpr std::size_t kBatch = 32;
  struct Batch {
    std::vector<std::int64_t> ids;
    std::vector<analysis::PreparedTrial> trials;
  };
  struct Skill {
    explicit Skill(analysis::TrialScorer s) : scorer(std::move(s)) {}
    analysis::TrialScorer scorer;
    Batch waiting;
  };

  void score(const Skill& skill, const Batch& batch) {
    if (batch.ids.empty()) return;
    const std::vector<analysis::TrialScore> scores = skill.scorer.scorePrepared(batch.trials);
    const std::lock_guard lock(mutex_);
    for (std::size_t i = 0; i < scores.size(); ++i) scores_[batch.ids[i]] = scores[i];
  }

  bool every_trial_;
  std::set<int> analyzed_recall_;  ///< empty: every recall trial (the "exclude" policy's spares)
  std::map<std::string, Skill> skills_;
  std::mutex mutex_;
  std::map<std::int64_t, analysis::TrialScore> scores_;
};

/// The outcome of a metric not analyzed (PowerOptions::score_shape, score_force): NaN.
report::MetricOutcome notAnalyzed(const report::PowerPlan& plan) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  return {kNaN, kNaN, std::vector<double>(plan.pairs().size(), kNaN)};
}

/// One kinematic measure of each trial, from its recording as it ends (none when `name` is
/// empty). Called from the subjects' threads.
class KinematicsAsTheyEnd {
 public:
  explicit KinematicsAsTheyEnd(std::string name) : name_(std::move(name)) {}
  [[nodiscard]] bool active() const noexcept { return !name_.empty(); }

  void add(const session::TrialRecord& trial, const HapticProfile& profile) {
    if (!active()) return;
    const nlohmann::json value = analysis::toJson(analysis::trialKinematics(profile))[name_];
    const std::lock_guard lock(mutex_);
    values_[trial.id] = value.is_number() ? value.get<double>() : kNaN;
  }

  /// The trial's measure; NaN when none was measured.
  [[nodiscard]] double of(std::int64_t trial_id) const {
    const auto found = values_.find(trial_id);
    return found != values_.end() ? found->second : kNaN;
  }

 private:
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string name_;
  std::mutex mutex_;
  std::map<std::int64_t, double> values_;
};

/// The paper's form: a replicate's analyzed recall trials as ReplicateOutcome::trials keeps them.
std::vector<report::AnalyzedTrial> paperTrials(const report::StudyAnalysis& analysis,
                                               const KinematicsAsTheyEnd& kinematics) {
  std::vector<report::AnalyzedTrial> trials;
  for (const auto& c : analysis.costs) {
    trials.push_back({c.trial_id, c.subject, c.mode, c.trial, c.trajectory(), c.forceProfile(), kinematics.of(c.trial_id)});
  }
  return trials;
}

}  // namespace

PowerStudy::PowerStudy(const PowerOptions& options) : options_(options) {
  checkOptions(options_);
  std::sort(options_.subject_counts.begin(), options_.subject_counts.end());
  if (!options_.study.empty()) {
    study_ = session::loadStudy(options_.study);
    checkStudy(study_, options_.study);
    recordNamedExperts(study_);
  } else {
    HATTR_THROW_UNLESS(options_.recall_trials >= 2 && options_.training_trials >= 0,
                       "trials: expected >= 2 recall and >= 0 training, got {} and {}", options_.recall_trials,
                       options_.training_trials);
  }
  scratch_.emplace(options_.scratch, "power");
  if (options_.study.empty()) {
    study_ = writePaperStudy(scratch_->path(), {.glyph = options_.glyph, .subjects = options_.subject_counts.back(),
                                             .seed = options_.seed, .training_trials = options_.training_trials,
                                             .recall_trials = options_.recall_trials});
  }
  subject_options_ = study_.subjects.front().options;
  for (const auto& s : study_.subjects) group_options_.try_emplace(s.group, s.options);
  if (!options_.hypothesis.empty()) {
    for (nlohmann::json* o : {&subject_options_, &group_options_[study_.subjects.front().group]}) {
      o->erase("model");
      (*o)["hypothesis"] = options_.hypothesis;
    }
    for (auto& [group, o] : group_options_) {
      o.erase("model");
      o["hypothesis"] = options_.hypothesis;
    }
  }
  study_.subjects.clear();
  // A design: the phase compared, and between groups or strategies within subjects.
  if (!study_.paper_form) {
    tested_phase_ = testedPhase(study_, options_.phase);
    between_groups_ = study_.groups.size() > 1;
    HATTR_THROW_UNLESS(between_groups_ || study_.groups.front().strategies.size() > 1,
                       "{}: one group with one strategy: a power analysis needs something to compare (groups, or "
                       "strategies within subjects)", options_.study.string());
    const std::size_t most = study_.groups.size() * static_cast<std::size_t>(options_.subject_counts.back());
    HATTR_THROW_UNLESS(most <= 999, "subjects: {} per group in {} groups: expected at most 999 subjects in all, got {}",
                       options_.subject_counts.back(), study_.groups.size(), most);
  } else {
    HATTR_THROW_UNLESS(options_.phase.empty(), "--phase: only for a design of groups and sessions; the paper's "
                       "analysis compares the recall trials");
  }

  // The plan: what makes replicates the same, so not where the expert's file is.
  nlohmann::json definition = session::studyToJson(study_);
  definition.erase("subjects");
  definition.erase("experts");
  // Who the subjects are is part of the plan: replicates under another model do not merge.
  const auto named = [&](const char* key) {
    const auto& value = subject_options_[key];
    return value.is_string() ? value.get<std::string>() : value.dump();
  };
  definition["trainee"] = subject_options_.contains("model")         ? "model " + named("model")
                          : subject_options_.contains("hypothesis") ? named("hypothesis")
                                                                     : std::string("position-plan");
  if (!tested_phase_.empty()) definition["tested_phase"] = tested_phase_;
  plan_.study = definition;
  if (between_groups_) {
    for (const auto& g : study_.groups) plan_.modes.push_back(g.name);
  } else if (!study_.paper_form) {
    for (const auto mode : study_.groups.front().strategies) plan_.modes.emplace_back(guidance::modeName(mode));
  } else {
    for (const auto mode : study_.modes) plan_.modes.emplace_back(guidance::modeName(mode));
  }
  plan_.subject_counts = options_.subject_counts;
  plan_.replicates = options_.replicates;
  plan_.seed = options_.seed;
  plan_.alpha = options_.alpha;
}

report::ReplicateOutcome PowerStudy::runReplicate(int replicate, const std::function<void(double)>& progress) const {
  return runReplicate(replicate, {.subjects_at_once = options_.threads, .designs = plan_.subject_counts}, progress);
}

std::vector<report::ReplicateOutcome> PowerStudy::runReplicates(std::span<const int> replicates,
                                                                const std::function<void(double)>& progress) const {
  return runReplicates(replicates, plan_.subject_counts, progress);
}

std::vector<report::ReplicateOutcome> PowerStudy::runDesign(std::span<const int> replicates, int subjects,
                                                            const std::function<void(double)>& progress) const {
  HATTR_THROW_UNLESS(subjects >= 3 && subjects <= plan_.subject_counts.back(),
                     "power: a design of {} subjects: expected 3 to {} (the largest design)", subjects,
                     plan_.subject_counts.back());
  const std::array<int, 1> design{subjects};
  return runReplicates(replicates, design, progress);
}

double PowerStudy::labSecondsPerSubject(double session_setup_s) const {
  // Each skill's expert's duration, the trial's expected length.
  std::map<std::string, double> expert_s;
  for (const auto& [skill, file] : study_.experts) {
    const auto named = study_.named_expert_profiles.find(skill);
    expert_s[skill] = (named != study_.named_expert_profiles.end() ? named->second : io::readProfileCsv(file)).duration_s();
  }
  double seconds = 0.0;
  for (const auto& session : study_.schedule) {
    seconds += session_setup_s;
    for (const auto& block : session.blocks) {
      const auto skill = expert_s.find(block.skill.empty() ? study_.skill : block.skill);
      const double trial_s = skill != expert_s.end() ? skill->second : 0.0;
      seconds += block.trials * (trial_s + block.rest_s);
    }
  }
  return seconds;
}

std::vector<report::ReplicateOutcome> PowerStudy::runReplicates(std::span<const int> replicates,
                                                                std::span<const int> designs,
                                                                const std::function<void(double)>& progress) const {
  std::vector<report::ReplicateOutcome> outcomes(replicates.size());
  const std::set<int> distinct(replicates.begin(), replicates.end());
  HATTR_THROW_UNLESS(distinct.size() == replicates.size(), "power: a replicate is given twice (each has its own "
                     "scratch folder)");
  const auto workers = static_cast<std::size_t>(options_.threads);
  if (replicates.size() < workers) {
    // Fewer replicates than threads: one at a time, its subjects at once.
    std::optional<session::TrialEnvironment> environment;
    for (std::size_t k = 0; k < replicates.size(); ++k) {
      outcomes[k] = runReplicate(replicates[k],
                                 {.subjects_at_once = options_.threads, .environment = &environment, .designs = designs},
                                 [&](double fraction) {
                                   if (progress) progress(static_cast<double>(k) + fraction);
                                 });
    }
    return outcomes;
  }
  // A replicate per thread, its subjects one after the other, each thread keeping its paper:
  // the analysis too runs on both cores, and the outcomes are the same to the bit.
  std::atomic<std::size_t> next{0};
  std::mutex progress_mutex;
  std::vector<double> fractions(replicates.size(), 0.0);
  std::atomic<bool> failed{false};
  std::exception_ptr failure;
  const auto work = [&] {
    std::optional<session::TrialEnvironment> environment;
    for (std::size_t k = next++; k < replicates.size() && !failed; k = next++) {
      try {
        outcomes[k] = runReplicate(replicates[k], {.subjects_at_once = 1, .environment = &environment, .designs = designs},
                                   [&](double fraction) {
                                     const std::lock_guard lock(progress_mutex);
                                     fractions[k] = fraction;
                                     if (progress) progress(std::accumulate(fractions.begin(), fractions.end(), 0.0));
                                   });
      } catch (...) {
        const std::lock_guard lock(progress_mutex);
        if (!failure) failure = std::current_exception();
        failed = true;
      }
    }
  };
  std::vector<std::thread> threads;
  try {
    for (std::size_t w = 1; w < workers; ++w) threads.emplace_back(work);
  } catch (...) {  // no thread for this one: the others stop, and the error is the run's
    failed = true;
    for (auto& t : threads) t.join();
    throw;
  }
  work();
  for (auto& t : threads) t.join();
  if (failure) std::rethrow_exception(failure);
  return outcomes;
}

report::ReplicateOutcome PowerStudy::runReplicate(int replicate, const ReplicateRun& how,
                                                  const std::function<void(double)>& progress) const {
  HATTR_THROW_UNLESS(replicate >= 0 && replicate < plan_.replicates, "power: replicate {}: expected 0 to {}", replicate,
                     plan_.replicates - 1);
  // The largest design's subjects, seeded as the in-silico study with seed + r.
  session::StudyDefinition study = study_;
  study.subjects = replicateSubjects(replicate, how.designs.back());
  const std::filesystem::path folder = scratch_->path() / fmt::format("replicate-{}", replicate);
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  const std::filesystem::path file = folder / "study.sqlite";
  report::StudyAnalysis analysis;
  std::optional<report::ReplicateOutcome> design;
  std::vector<report::AnalyzedTrial> kept;  ///< the paper's form: its analyzed trials, when kept
  {
    (void)session::StudyDatabase::create(file, study);
    // Scored as the trials end, the store keeps no samples (unless the study stores them at a
    // resolution: then its subjects learn from what was stored, read back).
    const bool scratch = study.resolution.empty();
    session::StudyDatabase db = session::StudyDatabase::open(file, session::OpenMode::kRunner, {.scratch = scratch});
    session::StudyRunner runner(db, [](const session::SubjectRecord& s, const HapticProfile& expert) {
      return makeSimulatedParticipant(s, expert);
    });
    // The paper's form analyzes the metrics asked for (a design's analysis reads both).
    const report::AnalysisOptions analysis_options{.threads = static_cast<unsigned>(how.subjects_at_once),
                                                   .analyze_trajectory = !study.paper_form || options_.score_shape,
                                                   .analyze_force = !study.paper_form || options_.score_force};
    ScoredAsTheyEnd scored(db, !study.paper_form, analysis_options);
    KinematicsAsTheyEnd kinematics(options_.keep_trials ? options_.kinematic : "");
    if (how.environment && !*how.environment) {
      how.environment->emplace(study.device, render::parseWorldConfig(study.world.dump(), "study world"), study.rate_hz);
    }
    const double total = static_cast<double>(db.trials().size());
    int done = 0;
    session::RunOptions run;
    run.subjects_at_once = how.subjects_at_once;
    run.environment = how.environment ? &**how.environment : nullptr;
    run.progress = [&](const session::RunProgress&) {
      if (progress) progress(++done / total);
    };
    if (scratch || kinematics.active()) {
      run.stored = [&](const session::TrialRecord& t, const HapticProfile& p) {
        if (scratch) scored.add(t, p);
        kinematics.add(t, p);
      };
    }
    (void)runner.run(run);
    std::map<std::int64_t, analysis::TrialScore> scores;
    if (scratch) scores = scored.finish();
    report::AnalysisOptions options = analysis_options;
    options.scored = scratch ? &scores : nullptr;
    if (study.paper_form) {
      analysis = report::analyzeStudy(db, options);
      if (options_.keep_trials) kept = paperTrials(analysis, kinematics);
    } else {
      design = designOutcome(replicate, db, options, how.designs);
      for (auto& t : design->trials) t.kinematic = kinematics.of(t.trial_id);
    }
  }
  std::filesystem::remove_all(folder);
  if (design) return *design;

  // Each design: the replicate's first N subjects (S01 .. SN).
  report::ReplicateOutcome outcome{replicate, {}, std::move(kept)};
  for (const int n : how.designs) {
    std::set<std::string> ids;
    for (const auto& s : simulatedSubjects(n, 0, {})) ids.insert(s.id);
    std::vector<report::TrialCost> costs;
    std::copy_if(analysis.costs.begin(), analysis.costs.end(), std::back_inserter(costs),
                 [&ids](const report::TrialCost& c) { return ids.contains(c.subject); });
    const auto metric = [&](bool analyzed, bool trajectory) {
      return analyzed ? report::metricOutcome(report::analyzeMetric(trajectory ? "trajectory" : "force", costs, trajectory), plan_)
                      : notAnalyzed(plan_);
    };
    outcome.designs.push_back({metric(options_.score_shape, true), metric(options_.score_force, false)});
  }
  return outcome;
}

std::vector<session::SubjectSpec> PowerStudy::replicateSubjects(int replicate, int per_group) const {
  const std::uint64_t seed = plan_.seed + static_cast<std::uint64_t>(replicate);
  if (study_.paper_form) return simulatedSubjects(per_group, seed, subject_options_);
  // Per group, GROUP01 ...; seeds as the in-silico study's, numbered across the groups of the
  // largest design (a smaller design's subjects are the first of each group's).
  const auto largest = static_cast<std::uint64_t>(plan_.subject_counts.back());
  std::vector<session::SubjectSpec> subjects;
  for (std::size_t g = 0; g < study_.groups.size(); ++g) {
    const auto& group = study_.groups[g];
    for (int i = 1; i <= per_group; ++i) {
      const auto position = g * largest + static_cast<std::uint64_t>(i);
      subjects.push_back({fmt::format("{}{:02}", group.name, i), "simulated", seed * 1000 + position,
                          group_options_.at(group.name), group.name});
    }
  }
  return subjects;
}

std::vector<report::AnalyzedTrial> PowerStudy::analyzedTrials(
    const std::vector<const report::DesignTrialScore*>& tested) const {
  // The conditions compared: the groups, or the strategies within subjects (as designOutcome's).
  std::vector<report::AnalyzedTrial> trials;
  for (const auto* s : tested) {
    if (!between_groups_ && s->strategy == "none") continue;
    trials.push_back({s->trial_id, s->subject, between_groups_ ? s->group : s->strategy, s->trial_in_phase, s->shape(),
                      s->force(), std::numeric_limits<double>::quiet_NaN()});
  }
  return trials;
}

report::ReplicateOutcome PowerStudy::designOutcome(int replicate, const session::StudyDatabase& db,
                                                  const report::AnalysisOptions& options,
                                                  std::span<const int> designs) const {
  const report::DesignAnalysis analysis = report::analyzeDesign(db, options);
  // Each subject's number within its group, from its id (GROUP01 ... GROUP100 ...).
  const auto number = [](const report::DesignTrialScore& s) { return std::stoi(s.subject.substr(s.group.size())); };
  report::ReplicateOutcome outcome{replicate, {}, {}};
  for (const int n : designs) {
    std::vector<const report::DesignTrialScore*> tested;
    for (const auto& s : analysis.scores) {
      if (s.phase == tested_phase_ && number(s) <= n) tested.push_back(&s);
    }
    if (options_.keep_trials && n == designs.back()) outcome.trials = analyzedTrials(tested);
    std::array<report::MetricOutcome, 2> metrics;
    for (const bool shape : {true, false}) {
      if (between_groups_) {
        // Between groups: each subject's mean, one-way ANOVA and Tukey HSD.
        analysis::OneWayData data = report::groupSubjectMeans(tested, shape);
        data.factor = "group";
        metrics[shape ? 0 : 1] = report::metricOutcome(analysis::oneWayAnova(data).row("group"),
                                                       analysis::tukeyHsdOneWay(data), plan_);
      } else {
        // Strategies within subjects: the paper's mode × subject analysis of the phase's trials.
        std::vector<report::TrialCost> costs;
        for (const auto* s : tested) {
          if (s->strategy != "none") costs.push_back({s->trial_id, s->subject, s->strategy, s->trial_in_phase, s->score, ""});
        }
        metrics[shape ? 0 : 1] =
            report::metricOutcome(report::analyzeMetric(shape ? "trajectory" : "force", costs, shape), plan_);
      }
    }
    outcome.designs.push_back(metrics);
  }
  return outcome;
}

}  // namespace hattr::sim
