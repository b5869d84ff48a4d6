#pragma once
/// What a recording may not hold and still be a good trial: the pen through the paper, the
/// device held at its force limit, the pen outside the device's workspace. Judged from the
/// recording itself after the trial (every sample the recorder kept), so a recording says what
/// happened to it whatever ran it: `hattr record`, `hattr train`, a study's trial, the studio.
/// The bounds and why: docs/realtime.md, "Physical events".

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/device_limits.hpp"
#include "hattr/core/haptic_profile.hpp"
#include "hattr/render/height_field.hpp"

namespace hattr::session {

/// The bounds a trial's recording is judged against.
struct PhysicalBounds {
  /// Deepest the pen tip may go under the paper's surface [m]: the paper's thickness
  /// (render::PaperParams::thickness_m; TrialEnvironment::physicalBounds). The paper pushes back
  /// with its stiffness (at most the device's, 1000 N/m by default), so the device's continuous
  /// force (1.75 N) holds the pen 1.75 mm deep: the default 3 mm is past what the device can hold.
  double paper_thickness_m = 0.003;
  /// Longest the device may hold up the paper at its force limit without a break [s]: the paper's
  /// reaction alone asks for the limit or more and the device commands it. Longer, and the hand
  /// pressed harder than the device renders: the paper gave way (guidance that meets the limit
  /// gives way first, by the safety path's design, and is not counted).
  double saturation_s = 0.1;
  /// The commanded force counts as at the limit from this fraction of it.
  double saturation_fraction = 0.99;
};

/// One kind of event: how many separate episodes, when the first began, the worst value.
struct PhysicalEvent {
  std::uint64_t count = 0;
  double first_s = -1.0;  ///< profile time the first episode began [s]; < 0: none
  double worst = 0.0;     ///< deepest [m], longest at the limit [s], farthest outside [m]
};

/// What a recording did that a good trial does not.
struct PhysicalEvents {
  PhysicalEvent penetration;  ///< the tip deeper than the paper's thickness under its surface: fallen through
  PhysicalEvent saturation;   ///< the paper held up at the force limit longer than PhysicalBounds::saturation_s
  PhysicalEvent workspace;    ///< the tip outside the device's workspace box
  [[nodiscard]] bool any() const noexcept {
    return penetration.count > 0 || saturation.count > 0 || workspace.count > 0;
  }
};

/// Judges every sample of `profile`: the surface is `relief` (flat: z = 0), the force limit
/// `force_limit_N` (the safety path's), the workspace `limits`'.
PhysicalEvents judgeRecording(const HapticProfile& profile, const DeviceLimits& limits, double force_limit_N,
                              const render::HeightField& relief, const PhysicalBounds& bounds = {});

/// The events for people, one phrase each ("the pen 186.0 mm under the paper at 1.234 s"),
/// joined by " · "; empty when none.
std::string describePhysicalEvents(const PhysicalEvents& events);

/// Why `profile` cannot serve as an expert, a reference or a hand script on a device of
/// `limits`: it presses harder than the device's continuous force (the device cannot hold the
/// paper up against it: the pen would sink through), it spans more than the device's workspace
/// on an axis, or it fits but lies outside it. One sentence per problem with the numbers and
/// the remedy; empty when it can.
std::vector<std::string> renderabilityProblems(const HapticProfile& profile, const DeviceLimits& limits);
/// Throws InputError "WHAT: PROBLEMS" (joined by "; ") when renderabilityProblems finds any.
void checkRenderable(const HapticProfile& profile, const DeviceLimits& limits, std::string_view what);

/// Writes the events into a recording's metadata (physical_penetration = "COUNT first FIRST_S
/// worst WORST" and the like, only those that happened).
void notePhysicalEvents(const PhysicalEvents& events, ProfileMetadata& metadata);

}  // namespace hattr::session
