#pragma once
/// The between-trial part of the scheduled strategies (FADING, ASSIST-AS-NEEDED,
/// PARTIAL-THEN-FULL; docs/training_modes.md "Scheduled strategies"): after each guided trial,
/// the law and gain of the next one, from the trials before it. It is a pure function of their
/// tracking errors, which a study stores with each trial (its metadata's tracking_rms_m), so a
/// study resumed after a crash schedules its next trial exactly as an unbroken run would.

#include <span>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/guidance/reference.hpp"
#include "hattr/guidance/training_guidance.hpp"

namespace hattr::guidance {

/// The law and gain of a scheduled strategy's next guided trial, `errors_before_m` holding the
/// tracking error of each guided trial of the same strategy before it, oldest first (its size
/// is the trial's number among them, from 0). Parameters from `config` (fading, assist,
/// partial_then_full). For a strategy that is not scheduled, config.scheduled as it is (unused).
[[nodiscard]] ScheduledLaw scheduleTrial(const GuidanceConfig& config, TrainingMode mode,
                                         std::span<const double> errors_before_m);

/// A trial's tracking error [m]: the root mean square, over its pen-down samples, of the
/// in-plane distance to the nearest pen-down point of the expert's path. Infinite when the
/// trial has no pen-down sample (nothing written: the largest error there is).
[[nodiscard]] double trackingErrorRms(const ReferenceTrajectory& reference, const HapticProfile& trial);

}  // namespace hattr::guidance
