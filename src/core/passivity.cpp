#include "hattr/core/passivity.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace hattr {

double passiveStiffnessBound(const DeviceLimits& limits, double rate_hz, double damping_N_s_per_m) {
  const double period_s = 1.0 / rate_hz;
  const double colgate = 2.0 * (limits.damping_N_s_per_m - std::abs(damping_N_s_per_m)) / period_s;
  const double sampled_mass = limits.mass_kg * (2.0 / period_s) * (2.0 / period_s);
  return std::max(0.0, std::min({limits.max_stiffness_N_per_m, colgate, sampled_mass}));
}

std::vector<std::string> clampImpedance(double& k, double& c, const ImpedanceClamp& what, const DeviceLimits& limits,
                                        double rate_hz) {
  const double k_before = k, c_before = c;
  std::string k_why, c_why;
  const auto lower = [](double& value, double bound, std::string& why, std::string_view reason) {
    bound = std::max(0.0, bound);
    if (value <= bound) return;
    value = bound;
    why += (why.empty() ? "" : ", then ") + std::string(reason);
  };
  const double period_s = 1.0 / rate_hz;
  lower(c, limits.max_damping_N_s_per_m - what.c_other_N_s_per_m, c_why, "device maximum damping");
  lower(k, limits.max_stiffness_N_per_m - what.k_other_N_per_m, k_why, "device maximum stiffness");
  const double room = limits.damping_N_s_per_m - (k + what.k_other_N_per_m) * period_s / 2.0 - what.c_other_N_s_per_m;
  if (c > room) lower(c, 0.8 * room, c_why, "Colgate's passivity bound b > K·T/2 + B");
  lower(k, passiveStiffnessBound(limits, rate_hz, c + what.c_other_N_s_per_m) - what.k_other_N_per_m, k_why,
        "Colgate's passivity bound b > K·T/2 + B");

  // One line per clamped value: from what, to what, why.
  std::vector<std::string> changes;
  if (k != k_before) {
    changes.push_back(fmt::format("{} {:.4g} N/m -> {:.4g} N/m: {}", what.stiffness_name, k_before, k, k_why));
  }
  if (c != c_before) {
    changes.push_back(fmt::format("{} {:.4g} N·s/m -> {:.4g} N·s/m: {}", what.damping_name, c_before, c, c_why));
  }
  return changes;
}

}  // namespace hattr
