#pragma once
/// What a device renders passively at its servo period T (Colgate & Schenkel): with b the
/// device's physical damping, a virtual stiffness K and damping B on one axis stay passive
/// while b > K·T/2 + B. Also K within the device's declared maximum, B within its declared
/// maximum, and K < m·(2/T)² (the sampled spring on the tip mass). Shared by the paper
/// renderer and the training modes, whose gains add up on the same axes.

#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/device_limits.hpp"

namespace hattr {

/// The largest stiffness [N/m] passive on `limits` at `rate_hz` with virtual damping
/// `damping_N_s_per_m` on the same axis.
double passiveStiffnessBound(const DeviceLimits& limits, double rate_hz, double damping_N_s_per_m);

/// An impedance to clamp: `k` and `c` are what the caller adds; `k_other`, `c_other` what is
/// already rendered on the same axis (e.g. the paper under the guidance).
struct ImpedanceClamp {
  std::string_view stiffness_name;  ///< for the report, e.g. "PCONTROL Kp"
  std::string_view damping_name;
  double k_other_N_per_m = 0.0;
  double c_other_N_s_per_m = 0.0;
};

/// Clamps k [N/m] and c [N·s/m] so that the sum with the others is passive: damping within
/// the device maximum, stiffness within its maximum, then damping within 80 % of the room
/// Colgate's bound leaves after the stiffness, then stiffness within the bound for that
/// damping. Returns one line per change ("PCONTROL Kd 170 N·s/m -> 0.46 N·s/m: ..."), in
/// SI units; empty when nothing changed.
std::vector<std::string> clampImpedance(double& k, double& c, const ImpedanceClamp& what, const DeviceLimits& limits,
                                        double rate_hz);

}  // namespace hattr
