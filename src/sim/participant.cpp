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

 private:
  /// Common random numbers: the same noise and pace for the same trial number in every mode.
  [[nodiscard]] std::uint64_t trialSeed(const session::TrialPlan& plan) const {
    return seed_ * 1'000'003ULL + (plan.phase == session::Phase::kTraining ? 0ULL : 500ULL) +
           static_cast<std::uint64_t>(plan.index);
  }

  std::uint64_t seed_;
  SimulatedTrainee trainee_;
  std::unique_ptr<device::HandScript> hand_;
};

}  // namespace

std::unique_ptr<session::Participant> makeSimulatedParticipant(const session::SubjectRecord& subject,
                                                               const HapticProfile& expert, const TraineeModel& model) {
  const auto& options = subject.spec.options;
  for (const auto& item : options.items()) {
    HATTR_THROW_UNLESS(item.key() == "template" || item.key() == "model",
                       "subject {}: unknown option \"{}\" for a simulated participant: expected template, model",
                       subject.id, item.key());
  }
  const HapticProfile script =
      options.contains("template") ? io::readProfileCsv(options["template"].get<std::string>()) : expert;
  return std::make_unique<SimulatedParticipant>(model, subject, script, expert);
}

std::unique_ptr<session::Participant> makeSimulatedParticipant(const session::SubjectRecord& subject,
                                                               const HapticProfile& expert) {
  const auto& options = subject.spec.options;
  const std::filesystem::path model_file = options.contains("model") ? std::filesystem::path(options["model"].get<std::string>())
                                                                     : defaultDataDir() / "sim" / "trainee_model.json";
  return makeSimulatedParticipant(subject, expert, loadTraineeModel(model_file));
}

std::unique_ptr<session::Participant> makeUnattendedParticipant(const session::SubjectRecord& subject,
                                                                const HapticProfile& expert) {
  if (subject.spec.participant == "script") return session::makeScriptParticipant(subject, expert);
  if (subject.spec.participant == "simulated") return makeSimulatedParticipant(subject, expert);
  if (subject.spec.participant == "person") {
    throw InputError(fmt::format("subject {} is a person: run their trials from the studio (hattr studio)", subject.id));
  }
  throw InputError(fmt::format("subject {}: participant \"{}\" is not available in this build", subject.id,
                               subject.spec.participant));
}

}  // namespace hattr::sim
