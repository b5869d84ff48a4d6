#pragma once
/// A simulated trainee as a study participant (session::Participant): the study runner asks
/// it for a hand for each trial and tells it each stored trial, from which it learns. The
/// mode enters only through the guidance force recorded in the trial (docs/simulation.md).

#include <memory>

#include "hattr/session/study_runner.hpp"
#include "hattr/sim/trainee.hpp"

namespace hattr::sim {

/// The participant for a subject with participant "simulated". Subject options:
///   "template": the expert's script (what the expert meant to write) the trainee learns;
///               default: the expert reference itself (see SimulatedTrainee on why the
///               script is better);
///   "model":    a trainee model file; default: data/sim/trainee_model.json;
///   "hypothesis": a learning hypothesis by name ("force-plan", ...): its model file in
///               data/sim (hypothesisModelFile); not together with "model".
/// The subject's traits are drawn with its seed; the expert reference is what the trainee
/// sees in training trials. Trial noise depends on the subject, the phase and the trial number
/// but not on the mode: common random numbers across modes.
std::unique_ptr<session::Participant> makeSimulatedParticipant(const session::SubjectRecord& subject,
                                                               const HapticProfile& expert);

/// The trainee model a simulated subject's options name (above); InputError for a bad option.
TraineeModel subjectTraineeModel(const session::SubjectRecord& subject);

/// As above with an explicit model (the sensitivity sweep varies it).
std::unique_ptr<session::Participant> makeSimulatedParticipant(const session::SubjectRecord& subject,
                                                               const HapticProfile& expert, const TraineeModel& model);

/// The participant a study runs without a person at the pen, by the subject's `participant`:
/// "script" (session::makeScriptParticipant) or "simulated" (above). A "person" is refused
/// (their trials run from the studio), as is any other kind: InputError naming the subject.
/// So is a force-plan trainee on a device other than sim:// (`device_uri`, the study's): its
/// grip and push are rendered by the simulated pen's own hand only; the plugin ABI's and the
/// network's hand commands do not carry them. `hattr study run` and Python's hattr.run_study use it.
std::unique_ptr<session::Participant> makeUnattendedParticipant(const session::SubjectRecord& subject,
                                                                const HapticProfile& expert,
                                                                std::string_view device_uri);

}  // namespace hattr::sim
