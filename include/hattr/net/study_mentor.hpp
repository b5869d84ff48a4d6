#pragma once
/// The expert's station for a study's mentored modes (MENTOR-OBSERVE, -POSITION, -FORCE,
/// -BILATERAL; docs/studies.md, docs/mentoring.md): what the study runner uses as a training
/// trial's live guidance (session::LiveGuidance).
///   simulated  a simulated expert writes the study's expert reference on a second simulated pen
///              with its own paper and safety path, ticked with the trainee's loop, over an
///              emulated link with the study's round trip, jitter and loss (seeded per trial, so a
///              resumed study is bit-identical);
///   live       a person at a station running `hattr mentor lead --sessions 0`, reached over UDP
///              with the shared key; each trial is one mentoring session.
/// The trainee's side is the study trial (a haptic profile like any other); what the coupling
/// did goes into its metadata.

#include <memory>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/net/mentor.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/study.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::net {

/// The coupling of a mentored mode (its position among the MENTOR-... modes). Throws
/// InputError for a paper mode.
Coupling couplingOfMode(guidance::TrainingMode mode);

/// The study's mentor (StudyDefinition::mentor): a simulated expert writing `expert` on
/// `world` at `rate_hz`, or a live one. Throws InputError for a bad address or key file.
std::unique_ptr<session::LiveGuidance> makeStudyMentor(const session::StudyMentor& mentor, const HapticProfile& expert,
                                                       const render::WorldConfig& world, double rate_hz);

}  // namespace hattr::net
