#include "hattr/sim/participant.hpp"

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/sim/data_dir.hpp"

namespace hattr::sim {
namespace {

class SimulatedParticipant final : public session::Participant {
 public:
  SimulatedParticipant(const TraineeModel& model, const session::SubjectRecord& subject, const HapticProfile& script,
                       const HapticProfile& shown)
      : seed_(subject.spec.seed), trainee_(model, drawSubject(model, subject.spec.seed), script, subject.spec.seed) {
    trainee_.setVisualTemplate(shown);
  }

  device::HandScript& handForTrial(const session::TrialPlan& plan) override {
    hand_ = trainee_.handForTrial(trialSeed(plan));
    return *hand_;
  }

  void trialCompleted(const session::TrialPlan& plan, const HapticProfile& recorded) override {
    // The trial's pace comes from its seed, so a resumed study relearns exactly as it learned.
    trainee_.learn(recorded, plan.view.show_reference, trainee_.paceFactor(trialSeed(plan)));
  }

  void daysPassed(int days) override { trainee_.restDays(days); }

 private:
  /// Common random numbers: the same noise and pace for the same trial number in every mode
  /// of a phase. Each session and each phase other than training and recall draws its own
  /// (the paper's one session draws as it always did).
  [[nodiscard]] std::uint64_t trialSeed(const session::TrialPlan& plan) const {
    return seed_ * 1'000'003ULL + (plan.phase == session::kPhaseTraining ? 0ULL : 500ULL) +
           static_cast<std::uint64_t>(plan.index) + 1'000ULL * phaseStream(plan.phase) +
           100'000ULL * static_cast<std::uint64_t>(plan.session);
  }

  /// 0 for training and recall, 1 to 4 for hattr's other phases, 5 to 93 for a free label.
  static std::uint64_t phaseStream(std::string_view phase) {
    constexpr std::string_view kNamed[] = {session::kPhaseBaseline, session::kPhasePostTest, session::kPhaseRetention,
                                           session::kPhaseTransfer};
    if (phase == session::kPhaseTraining || phase == session::kPhaseRecall) return 0;
    for (std::uint64_t i = 0; i < 4; ++i) {
      if (phase == kNamed[i]) return i + 1;
    }
    std::uint64_t hash = 14695981039346656037ULL;  // FNV-1a: the same label, the same stream everywhere
    for (const char c : phase) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
    return 5 + hash % 89;
  }

  std::uint64_t seed_;
  SimulatedTrainee trainee_;
  std::unique_ptr<device::HandScript> hand_;
};

}  // namespace

TraineeModel subjectTraineeModel(const session::SubjectRecord& subject) {
  const auto& options = subject.spec.options;
  const auto text = [&](const char* key) {
    const auto& value = options[key];
    HATTR_THROW_UNLESS(value.is_string(), "subject {}: option {}: expected a string, got {}", subject.id, key,
                       value.dump());
    return value.get<std::string>();
  };
  HATTR_THROW_UNLESS(!(options.contains("model") && options.contains("hypothesis")),
                     "subject {}: options model and hypothesis: expected one of them (a model file states its "
                     "hypothesis), got both",
                     subject.id);
  if (options.contains("model")) return loadTraineeModel(text("model"));
  if (options.contains("hypothesis")) {
    return loadHypothesisModel(parseHypothesis(text("hypothesis"), fmt::format("subject {}: option hypothesis", subject.id)));
  }
  return loadHypothesisModel(LearningHypothesis::kPositionPlan);
}

std::unique_ptr<session::Participant> makeSimulatedParticipant(const session::SubjectRecord& subject,
                                                               const HapticProfile& expert, const TraineeModel& model) {
  const auto& options = subject.spec.options;
  for (const auto& item : options.items()) {
    // "learner": a learner's details (session/learner.hpp), which a simulated learner may have too.
    HATTR_THROW_UNLESS(item.key() == "template" || item.key() == "model" || item.key() == "hypothesis" ||
                           item.key() == "learner",
                       "subject {}: unknown option \"{}\" for a simulated participant: expected template, model, "
                       "hypothesis or learner",
                       subject.id, item.key());
  }
  const HapticProfile script =
      options.contains("template") ? io::readProfileCsv(options["template"].get<std::string>()) : expert;
  return std::make_unique<SimulatedParticipant>(model, subject, script, expert);
}

std::unique_ptr<session::Participant> makeSimulatedParticipant(const session::SubjectRecord& subject,
                                                               const HapticProfile& expert) {
  return makeSimulatedParticipant(subject, expert, subjectTraineeModel(subject));
}

std::unique_ptr<session::Participant> makeUnattendedParticipant(const session::SubjectRecord& subject,
                                                                const HapticProfile& expert,
                                                                std::string_view device_uri) {
  if (subject.spec.participant == "script") return session::makeScriptParticipant(subject, expert);
  if (subject.spec.participant == "simulated") {
    const TraineeModel model = subjectTraineeModel(subject);
    HATTR_THROW_UNLESS(model.hypothesis != LearningHypothesis::kForcePlan || device_uri.starts_with("sim://"),
                       "subject {} is a force-plan trainee, whose grip and push only the simulated pen renders: "
                       "expected a sim:// device, got \"{}\"",
                       subject.id, device_uri);
    return makeSimulatedParticipant(subject, expert, model);
  }
  if (subject.spec.participant == "person") {
    throw InputError(fmt::format("subject {} is a person: run their trials from the studio (hattr studio)", subject.id));
  }
  throw InputError(fmt::format("subject {}: participant \"{}\" is not available in this build", subject.id,
                               subject.spec.participant));
}

}  // namespace hattr::sim
