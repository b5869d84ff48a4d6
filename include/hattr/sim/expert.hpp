#pragma once
/// The simulated expert: turns a glyph into the movement and force an expert means to
/// make (a "script"), then performs it on the simulated pen to give the expert's haptic
/// profile. SI units, frame W (docs/units_and_frames.md). Model and sources:
/// docs/simulation.md.
///
/// The script:
/// - each stroke is a minimum-jerk movement through its via points (Flash & Hogan 1985),
///   split into rest-to-rest sub-movements at sharp corners (turns above corner_angle_rad);
///   the via times within a sub-movement minimize the squared jerk;
/// - durations follow an isochrony-like rule T = c·L^β (longer movements are faster; Viviani
///   & McCollum 1983), with c chosen so the fastest sub-movement peaks at peak_speed_m_per_s;
/// - the pen lifts between strokes (pen_down false, a smooth rise to lift_height_m and back)
///   and travels with the same rule;
/// - the axial force rises smoothly at touch-down while the pen rests on the first point, holds
///   axial_force_N through the stroke and falls at the end before the lift;
/// - the pen's tilt is constant (altitude_rad, azimuth_rad).
/// Each sample stores f_user_W.z = −axial·sin(altitude) (the normal force the expert means to
/// exert), tilt, pen_down and in_contact = pen_down: what device::ProfileHandScript reads.

#include <numbers>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/session/study.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/sim/glyph.hpp"

namespace hattr::sim {

/// How the simulated expert writes. Every default is documented in docs/simulation.md with
/// its source or as an assumption.
struct ExpertConfig {
  double rate_hz = 1000.0;                  ///< script sampling rate (the servo rate)
  double peak_speed_m_per_s = 0.080;        ///< peak pen-tip speed of the fastest movement
  double isochrony_exponent = 0.5;          ///< β in T = c·L^β (1: constant speed; 0: constant time)
  double corner_angle_rad = std::numbers::pi / 3.0;  ///< turns sharper than this stop the pen (60°)
  double lift_height_m = 0.003;             ///< pen height between strokes (the hand lifts at least 3 mm)
  double min_transit_s = 0.15;              ///< shortest pen-up movement between strokes
  double lead_in_s = 0.3;                   ///< pen up, at rest above the first point, before writing
  double approach_s = 0.1;                  ///< lowering the pen onto the first point
  double retreat_s = 0.1;                   ///< lifting the pen off the last point
  double lead_out_s = 0.3;                  ///< pen up, at rest, after writing
  double axial_force_N = 1.2;               ///< axial pen force mid-stroke
  double touch_down_s = 0.15;               ///< force rise at touch-down, with the pen at rest
  double lift_off_s = 0.08;                 ///< force fall before lift-off, with the pen at rest
  double altitude_rad = 57.0 * std::numbers::pi / 180.0;  ///< pen axis above the paper
  double azimuth_rad = 135.0 * std::numbers::pi / 180.0;  ///< a right-hander's barrel toward the lower right
};

/// Checks a configuration; throws InputError naming the field, the allowed range and the value.
void validateExpertConfig(const ExpertConfig& config);

/// The expert's script for `glyph`: a profile sampled at config.rate_hz from t = 0, with tilt
/// channels, metadata subject "expert", skill glyph.name, source "sim:expert-script". Throws
/// InputError for a bad configuration or a glyph without strokes. Not for the servo thread.
HapticProfile expertScript(const Glyph& glyph, const ExpertConfig& config = {});

/// The expert's haptic profile: `script` played by a device::ProfileHandScript through
/// session::runTrial in BASIC mode (no guidance) for the script's duration, on the simulated
/// clock. `metadata` is the recording's (subject, skill, ...). Throws what runTrial throws.
HapticProfile recordExpert(session::TrialEnvironment& environment, const HapticProfile& script,
                           ProfileMetadata metadata);

/// Records the experts a study names by a glyph (StudyDefinition::named_experts: a built-in
/// glyph's name or its character) into study.named_expert_profiles: the simulated expert's
/// script for the glyph performed on the study's pen (a sim:// one; else the simulated pen),
/// world and rate, with the skill's name. Throws InputError naming the skill and listing the
/// built-in glyphs for a name that is none.
void recordNamedExperts(session::StudyDefinition& study);

}  // namespace hattr::sim
