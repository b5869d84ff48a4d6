#pragma once
/// A pen tablet as the hand (Qt's QTabletEvent): pressure and tilt as Qt reports them,
/// converted to the hand's axial force and pen angles in one place. Qt gives pressure in
/// 0..1 and xTilt / yTilt in degrees (positive toward the tablet's right and toward the
/// writer); the force goes through io::TabletCalibration, as the tablet importers do.
/// GUI thread; no Qt types, so it is tested without widgets.

#include <filesystem>

#include "hattr/io/tablet_import.hpp"

namespace hattr::studio {

/// The pen's angles in the hand command's convention (hattr::io::axialForceOnPaper):
/// altitude above the paper, azimuth clockwise from W's +y to the barrel's projection.
struct PenAngles {
  double altitude_rad = 1.5707963267948966;
  double azimuth_rad = 0.0;
};

/// The lowest altitude the tablet hand holds (a pen lying almost flat is clamped) [rad].
inline constexpr double kTabletMinAltitude_rad = 0.17453292519943295;  // 10°

/// Pen angles from Qt's tilts [deg]: the barrel direction is (tan xTilt, −tan yTilt, 1) in
/// W (Qt's y grows toward the writer, W's away); altitude = 90° − its angle from the
/// vertical (clamped to [kTabletMinAltitude_rad, 90°]), azimuth = atan2(x, y) in [0, 2π).
/// Non-finite tilts give an upright pen.
PenAngles penAnglesFromTilt(double x_tilt_deg, double y_tilt_deg) noexcept;

/// The studio's tablet calibration: svc2004Calibration() (its pressure_max_N, full scale at
/// Qt's pressure 1.0), named for the studio.
io::TabletCalibration defaultTabletCalibration();

/// Axial force [N] for Qt's pressure (0..1): pressureToNewtons(pressure · pressure_max_raw).
double tabletPressureToNewtons(double pressure, const io::TabletCalibration& calibration);

/// A calibration JSON over the studio's defaults (io::loadCalibration); throws InputError.
io::TabletCalibration loadTabletCalibration(const std::filesystem::path& file);

}  // namespace hattr::studio
