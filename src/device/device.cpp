#include "hattr/device/device.hpp"

#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::device {

// Only device-clocked devices own a clock; asking any other device is a bug in the caller.
void Device::startClock(DeviceTickFn /*tick*/, void* /*context*/) {
  throw Error(fmt::format("device {} does not run a clock of its own", uri()));
}

void checkReportedLimits(const DeviceLimits& l, std::string_view who) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  const auto nonneg = [](double v) { return std::isfinite(v) && v >= 0.0; };
  HATTR_THROW_UNLESS(positive(l.peak_force_N) && positive(l.continuous_force_N) && l.continuous_force_N <= l.peak_force_N &&
                         positive(l.max_stiffness_N_per_m) && nonneg(l.max_damping_N_s_per_m) &&
                         positive(l.nominal_rate_hz) && positive(l.mass_kg) && nonneg(l.damping_N_s_per_m) &&
                         l.workspace_min_m.allFinite() && l.workspace_max_m.allFinite() &&
                         (l.workspace_min_m.array() < l.workspace_max_m.array()).all(),
                     "{} reports invalid limits (expected finite positive forces, stiffness, rate and mass, "
                     "continuous <= peak force, a workspace box with min < max; got peak {} N, continuous {} N, "
                     "stiffness {} N/m, rate {} Hz, mass {} kg)",
                     who, l.peak_force_N, l.continuous_force_N, l.max_stiffness_N_per_m, l.nominal_rate_hz, l.mass_kg);
}

}  // namespace hattr::device
