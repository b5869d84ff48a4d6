#include "core/tablet_input.hpp"

#include <algorithm>
#include <cmath>

namespace hattr::studio {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kDegToRad = kPi / 180.0;

}  // namespace

PenAngles penAnglesFromTilt(double x_tilt_deg, double y_tilt_deg) noexcept {
  PenAngles angles;
  if (!std::isfinite(x_tilt_deg) || !std::isfinite(y_tilt_deg)) return angles;
  // Barrel direction in W per unit height: Qt's y toward the writer is W's −y.
  const double bx = std::tan(std::clamp(x_tilt_deg, -89.0, 89.0) * kDegToRad);
  const double by = -std::tan(std::clamp(y_tilt_deg, -89.0, 89.0) * kDegToRad);
  const double tilt_rad = std::atan(std::hypot(bx, by));
  angles.altitude_rad = std::clamp(0.5 * kPi - tilt_rad, kTabletMinAltitude_rad, 0.5 * kPi);
  double azimuth = std::atan2(bx, by);
  if (azimuth < 0.0) azimuth += 2.0 * kPi;
  angles.azimuth_rad = azimuth;
  return angles;
}

io::TabletCalibration defaultTabletCalibration() {
  io::TabletCalibration cal = io::svc2004Calibration();
  cal.name = "studio tablet (Qt pressure 0..1 at svc2004's full scale, " + std::to_string(cal.pressure_max_N) + " N)";
  return cal;
}

double tabletPressureToNewtons(double pressure, const io::TabletCalibration& calibration) {
  const double p = std::isfinite(pressure) ? std::clamp(pressure, 0.0, 1.0) : 0.0;
  return io::pressureToNewtons(p * calibration.pressure_max_raw, calibration);
}

io::TabletCalibration loadTabletCalibration(const std::filesystem::path& file) {
  return io::loadCalibration(file, defaultTabletCalibration());
}

}  // namespace hattr::studio
