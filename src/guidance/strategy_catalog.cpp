#include "hattr/guidance/strategy_catalog.hpp"

#include <charconv>
#include <cmath>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/core/error.hpp"

namespace hattr::guidance {
namespace {

std::vector<StrategyInfo> makeCatalog() {
  using M = TrainingMode;
  return {
      {M::kBasic, "Free writing", "No force: the trainee writes on the virtual paper alone.",
       "the paper's BASIC mode (Srimathveeravalli & Kesavadas, section 4)", false, {}},
      {M::kPositionControl, "Guided path",
       "A spring and damper pull the pen toward where the expert's pen was at this moment, in the paper plane.",
       "the paper's PCONTROL mode: PD position guidance, gains from the paper", false,
       {{"kp_N_per_mm", "N/mm", 0.35, 0.0, 2.0, "spring toward the expert's point"},
        {"kd_N_s_per_mm", "N·s/mm", 0.17, 0.0, 1.0, "damper toward the expert's velocity"}}},
      {M::kForceControl, "Guided pressure",
       "The pen is pushed so that the trainee's force follows the force the expert applied at this moment.",
       "the paper's ALPHA mode: PD force guidance from the haptic profile, gains from the paper", false,
       {{"kp", "1", 0.5, 0.0, 5.0, "gain on the force error"},
        {"kd_s", "s", 0.1, 0.0, 1.0, "gain on the force error's rate"},
        {"derivative_cutoff_hz", "Hz", 20.0, 1.0, 200.0, "low-pass on the force error's rate"}}},
      {M::kMentorObserve, "Feel the teacher",
       "The trainee's pen follows a live teacher's pen at another station; the teacher feels nothing.",
       "hattr's mentoring (docs/mentoring.md); a one-way position coupling", true, {}},
      {M::kMentorPosition, "Teacher guides the path",
       "A live teacher's pen pulls the trainee's pen toward it; the teacher feels the trainee.",
       "hattr's mentoring (docs/mentoring.md); position coupling with force feedback", true, {}},
      {M::kMentorForce, "Teacher guides the pressure",
       "The trainee's force is guided toward the force a live teacher applies.",
       "hattr's mentoring (docs/mentoring.md); ALPHA's law on a live expert's force", true, {}},
      {M::kMentorBilateral, "Write together",
       "Teacher and trainee pens are coupled both ways, each feeling the other.",
       "hattr's mentoring (docs/mentoring.md); a bilateral position–position coupling", true, {}},
      {M::kChannel, "Stay on the path",
       "No force while the pen stays within a narrow channel around the expert's path; outside, a spring "
       "pushes it back.",
       "haptic channel / bandwidth guidance (a virtual fixture): Marchal-Crespo & Reinkensmeyer (guidance "
       "with a dead band around the path); the width and stiffness are hattr's choices, the stiffness the "
       "paper's PCONTROL Kp",
       false,
       {{"half_width_mm", "mm", 2.0, 0.0, 20.0, "half-width of the channel: no force within it"},
        {"kp_N_per_mm", "N/mm", 0.35, 0.0, 2.0, "spring beyond the channel's wall"},
        {"kd_N_s_per_mm", "N·s/mm", 0.0, 0.0, 1.0, "damper across the wall, outside"},
        {"search_s", "s", 0.5, 0.01, 5.0, "the expert's path searched around the current moment"}}},
      {M::kErrorAugmentation, "Feel your mistakes",
       "The pen is pushed further away from the expert's point, so that deviations are felt larger.",
       "error augmentation (Patton et al. 2006; Milot et al. 2010): a force proportional to the "
       "deviation, saturated; the gain and saturation are hattr's choices, the gain bounded by the "
       "device's passivity",
       false,
       {{"gain_N_per_mm", "N/mm", 0.1, 0.0, 1.0, "force per millimetre of deviation, away from the path"},
        {"saturation_mm", "mm", 10.0, 0.5, 50.0, "deviations beyond this count as this"}}},
      {M::kNoise, "Steady hand",
       "A gentle random push in the paper plane, different every moment, that the trainee learns to "
       "resist.",
       "noise-like haptic disturbance (Lee & Choi 2010): Gaussian, low-pass filtered, seeded per trial and "
       "recorded as the guidance force; the level and band are hattr's choices",
       false,
       {{"rms_N", "N", 0.3, 0.0, 2.0, "root-mean-square force on each axis of the plane"},
        {"cutoff_hz", "Hz", 5.0, 0.1, 100.0, "first-order low-pass of the white noise"}}},
      {M::kPlayback, "Feel the expert's hand",
       "The force the expert applied is pushed onto the pen as it was recorded, whatever the trainee does.",
       "record and play, open loop (Yokokohji et al.; Henmi & Yoshikawa), the approach the paper contrasts "
       "ALPHA with",
       false, {{"gain", "1", 1.0, 0.0, 3.0, "share of the expert's force played"}}},
  };
}

/// Where a parameter lives in a configuration, and its unit's size in SI.
struct Binding {
  double* value = nullptr;
  double si_per_unit = 1.0;
};

Binding bind(GuidanceConfig& c, TrainingMode mode, std::string_view name) {
  constexpr double kPerMm = 1000.0;  // N/mm -> N/m, N·s/mm -> N·s/m
  constexpr double kMm = 1e-3;       // mm -> m
  using M = TrainingMode;
  const auto is = [&](M m, std::string_view n) { return mode == m && name == n; };
  if (is(M::kPositionControl, "kp_N_per_mm")) return {&c.position.kp_N_per_m, kPerMm};
  if (is(M::kPositionControl, "kd_N_s_per_mm")) return {&c.position.kd_N_s_per_m, kPerMm};
  if (is(M::kForceControl, "kp")) return {&c.force.kp, 1.0};
  if (is(M::kForceControl, "kd_s")) return {&c.force.kd_s, 1.0};
  if (is(M::kForceControl, "derivative_cutoff_hz")) return {&c.force.derivative_cutoff_hz, 1.0};
  if (is(M::kChannel, "half_width_mm")) return {&c.channel.half_width_m, kMm};
  if (is(M::kChannel, "kp_N_per_mm")) return {&c.channel.kp_N_per_m, kPerMm};
  if (is(M::kChannel, "kd_N_s_per_mm")) return {&c.channel.kd_N_s_per_m, kPerMm};
  if (is(M::kChannel, "search_s")) return {&c.channel.search_s, 1.0};
  if (is(M::kErrorAugmentation, "gain_N_per_mm")) return {&c.augmentation.gain_N_per_m, kPerMm};
  if (is(M::kErrorAugmentation, "saturation_mm")) return {&c.augmentation.saturation_m, kMm};
  if (is(M::kNoise, "rms_N")) return {&c.noise.rms_N, 1.0};
  if (is(M::kNoise, "cutoff_hz")) return {&c.noise.cutoff_hz, 1.0};
  if (is(M::kPlayback, "gain")) return {&c.playback_force.gain, 1.0};
  return {};
}

const StrategyParameter& findParameter(TrainingMode mode, std::string_view name) {
  const StrategyInfo& info = strategyInfo(mode);
  for (const auto& p : info.parameters) {
    if (p.name == name) return p;
  }
  std::vector<std::string_view> names;
  for (const auto& p : info.parameters) names.push_back(p.name);
  throw InputError(fmt::format("{}: no parameter \"{}\": expected {}", modeName(mode), name,
                               names.empty() ? std::string("none (it has no parameters)")
                                             : fmt::format("one of {}", fmt::join(names, ", "))));
}

}  // namespace

const std::vector<StrategyInfo>& strategyCatalog() {
  static const std::vector<StrategyInfo> catalog = makeCatalog();
  return catalog;
}

const StrategyInfo& strategyInfo(TrainingMode mode) {
  for (const auto& info : strategyCatalog()) {
    if (info.mode == mode) return info;
  }
  throw Error(fmt::format("strategy {} is not in the catalog", static_cast<int>(mode)));
}

void setStrategyParameter(GuidanceConfig& config, TrainingMode mode, std::string_view name, double value) {
  const StrategyParameter& p = findParameter(mode, name);
  HATTR_THROW_UNLESS(std::isfinite(value) && value >= p.min && value <= p.max,
                     "{} {}: expected {} to {} {}, got {}", modeName(mode), name, p.min, p.max, p.unit, value);
  const Binding b = bind(config, mode, name);
  HATTR_DEMAND(b.value != nullptr, "strategy parameter {} {} has no place in GuidanceConfig", modeName(mode), name);
  *b.value = value * b.si_per_unit;
}

StrategySetting parseStrategySetting(std::string_view text) {
  const auto equals = text.find('=');
  const std::string_view key = text.substr(0, std::min(equals, text.size()));
  std::string_view number = equals == std::string_view::npos ? std::string_view() : text.substr(equals + 1);
  if (number.starts_with('+')) number.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), value);
  const bool whole = !number.empty() && end == number.data() + number.size();
  HATTR_THROW_UNLESS(!key.empty() && whole && (ec == std::errc() || ec == std::errc::result_out_of_range),
                     "--param \"{}\": expected KEY=NUMBER (e.g. half_width_mm=1.5)", text);
  if (ec == std::errc::result_out_of_range) value = number.starts_with('-') ? -INFINITY : INFINITY;
  return {std::string(key), value};
}

void setStrategyParameters(GuidanceConfig& config, TrainingMode mode, std::span<const StrategySetting> settings) {
  std::set<std::string_view> seen;
  for (const auto& [name, value] : settings) {
    HATTR_THROW_UNLESS(seen.insert(name).second, "{} {}: given twice", modeName(mode), name);
    setStrategyParameter(config, mode, name, value);
  }
}

double strategyParameter(const GuidanceConfig& config, TrainingMode mode, std::string_view name) {
  (void)findParameter(mode, name);
  GuidanceConfig copy = config;
  const Binding b = bind(copy, mode, name);
  HATTR_DEMAND(b.value != nullptr, "strategy parameter {} {} has no place in GuidanceConfig", modeName(mode), name);
  return *b.value / b.si_per_unit;
}

}  // namespace hattr::guidance
