#pragma once
/// Importers for real pen-tablet recordings people already have: SVC2004 and SUSIG.
/// Tablet units, raw pressure and tilt convert to SI through a TabletCalibration, whose
/// defaults and sources are in docs/file-formats.md and which a JSON file can override.
/// Pen-up points are kept and flagged (pen_down = false), never dropped. A lift the tablet did
/// not report (no points in the air) but the format marks is one inserted pen-up sample, so
/// strokes are what the writer wrote (metadata `inserted_lift_samples`; docs/file-formats.md).
/// Errors throw hattr::InputError naming file, line and field. Not for the servo thread.

#include <filesystem>
#include <string>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::io {

/// How raw tablet values map to SI.
struct TabletCalibration {
  std::string name;                     ///< recorded in the profile's metadata
  double metres_per_unit_x = 1e-5;      ///< tablet x resolution [m per unit]
  double metres_per_unit_y = 1e-5;      ///< tablet y resolution [m per unit]
  bool y_axis_toward_writer = false;    ///< tablet y grows toward the writer (then flipped into W)
  double pressure_max_raw = 1023.0;     ///< raw value at full scale
  /// Axial force at full scale [N]: an assumption (see docs/file-formats.md), by default what the
  /// default device renders continuously, so an imported profile can guide and drive it.
  double pressure_max_N = 1.75;
  double pressure_exponent = 1.0;       ///< F = max_N·(raw / max_raw)^exponent
  double pen_down_pressure_raw = 0.0;   ///< the pen is down when raw pressure exceeds this
  double angle_rad_per_unit = 0.0;      ///< raw tilt units to rad (0: the format has no tilt)
  double default_altitude_rad = 1.5707963267948966;  ///< pen altitude when there is no tilt [rad]
  double time_s_per_unit = 1e-3;        ///< time-stamp unit [s]
  /// Places the writing on the paper: the centre of the pen-down points' box moves to W's origin
  /// (the paper's centre; the tablet's origin is a corner). The shift is in metadata `placed_shift_m`.
  bool centre_on_paper = true;
  friend bool operator==(const TabletCalibration&, const TabletCalibration&) = default;
};

/// Defaults for SVC2004 Task 2 (WACOM Intuos, 100 Hz, tilt in tenths of a degree).
TabletCalibration svc2004Calibration();
/// Defaults for SUSIG (Interlink ePad-ink, no tilt).
TabletCalibration susigCalibration();

/// Overrides fields of `defaults` from a JSON object whose keys are the field names above
/// (e.g. {"pressure_max_N": 3.5}). Unknown keys, wrong types and out-of-range values throw
/// InputError naming the key, the allowed range and the value.
TabletCalibration loadCalibration(const std::filesystem::path& file, TabletCalibration defaults);
TabletCalibration parseCalibration(std::string_view json_text, std::string_view source_name,
                                   TabletCalibration defaults);

/// Axial pen force [N] for a raw pressure value (clamped to the calibrated range).
double pressureToNewtons(double raw, const TabletCalibration& calibration);

/// The force the pen exerts on the paper for an axial force along the pen axis, in W:
/// the normal part is F·sin(altitude) (the paper's F_r = F·sin θ), the tangential part
/// F·cos(altitude) points from the barrel's projection toward the tip. Azimuth is
/// measured clockwise from W's +y axis to the barrel's projection.
Vec3 axialForceOnPaper(double axial_N, double azimuth_rad, double altitude_rad);

/// Imports an SVC2004 .TXT file: "N", then N lines "X Y T button azimuth altitude pressure".
/// The pen is down when pressure exceeds the threshold or button bit 0 is set. The tablet
/// reports nothing in the air: a lift precedes a point with button 0 that comes more than 1.5
/// median time steps after the one before (a dropped point keeps button 1). Time stamps
/// that do not increase (the tablet's clock jitters) are re-timed evenly between their
/// neighbours; how many is recorded in the metadata key `retimed_samples`.
HapticProfile importSvc2004(const std::filesystem::path& file, const TabletCalibration& calibration);
HapticProfile importSvc2004(std::istream& in, std::string_view source_name,
                            const TabletCalibration& calibration);

/// Imports a SUSIG file (format in docs/file-formats.md); EndPts = 1 ends a stroke.
HapticProfile importSusig(const std::filesystem::path& file, const TabletCalibration& calibration);
HapticProfile importSusig(std::istream& in, std::string_view source_name,
                          const TabletCalibration& calibration);

}  // namespace hattr::io
