#pragma once
/// Unit conversions at the edges. Inside hattr everything is SI (m, s, N, kg, N/m,
/// N·s/m, rad). Millimetres, the paper's N/mm gains, tablet units and degrees appear
/// only in files, importers and user interfaces, and are converted here, once.

#include <cmath>
#include <cstdint>
#include <numbers>

namespace hattr::units {

inline constexpr double kMetresPerMillimetre = 1e-3;
inline constexpr double kSecondsPerMillisecond = 1e-3;
inline constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;
/// Standard gravity [m/s²], for gram-force conversions.
inline constexpr double kStandardGravity_m_per_s2 = 9.80665;

constexpr double millimetresToMetres(double mm) { return mm / 1000.0; }
constexpr double metresToMillimetres(double m) { return m * 1000.0; }
constexpr double millisecondsToSeconds(double ms) { return ms * kSecondsPerMillisecond; }
constexpr double degreesToRadians(double deg) { return deg * kRadiansPerDegree; }
constexpr double radiansToDegrees(double rad) { return rad / kRadiansPerDegree; }
constexpr double gramForceToNewtons(double gf) { return gf * 1e-3 * kStandardGravity_m_per_s2; }

/// A duration in seconds as whole nanoseconds (rounded to the nearest), for clocks and timeouts.
inline std::int64_t secondsToNanoseconds(double s) noexcept { return static_cast<std::int64_t>(std::llround(s * 1e9)); }

inline constexpr double kMillimetresPerMetre = 1000.0;

/// A stiffness given in N/mm (the paper's unit) in N/m (0.35 N/mm -> exactly 350 N/m).
constexpr double newtonsPerMillimetreToSi(double n_per_mm) { return n_per_mm * kMillimetresPerMetre; }
/// A damping given in N·s/mm (the paper's unit) in N·s/m.
constexpr double newtonSecondsPerMillimetreToSi(double ns_per_mm) { return ns_per_mm * kMillimetresPerMetre; }

}  // namespace hattr::units
