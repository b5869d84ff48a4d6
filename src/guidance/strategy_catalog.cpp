#include "hattr/guidance/strategy_catalog.hpp"

#include <algorithm>
#include <cctype>
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
      {M::kFading, "Less help each time",
       "The guided path's (or pressure's) pull weakens trial by trial, or each time the trainee writes well, "
       "until the trainee writes alone.",
       "guidance fading, the field's answer to the guidance hypothesis (Salmoni, Schmidt & Walter 1984; "
       "Winstein, Pohl & Lewthwaite 1994); the linear and the performance schedule and their defaults are "
       "hattr's choices",
       false,
       {{"base", "", 0.0, 0.0, 1.0, "the guidance that fades", {"pcontrol", "alpha"}},
        {"by", "", 0.0, 0.0, 1.0, "fade over trials, or a step after each good trial", {"trials", "performance"}},
        {"start_gain", "1", 1.0, 0.0, 1.0, "share of the guidance in the first guided trial"},
        {"end_gain", "1", 0.0, 0.0, 1.0, "share it fades to"},
        {"trials", "trials", 10.0, 1.0, 1000.0, "by trials: the guided trial (from 1) that reaches end_gain"},
        {"step", "1", 0.2, 0.01, 1.0, "by performance: the fall after a good trial"},
        {"threshold_mm", "mm", 2.0, 0.1, 50.0, "by performance: a good trial's tracking error at most"}}},
      {M::kAssistAsNeeded, "Help when needed",
       "The pull toward the expert's writing grows after a trial with large errors and fades after good ones.",
       "assist-as-needed (Emken, Benitez & Reinkensmeyer 2007): an error-based update of the assistance with a "
       "forgetting factor, between trials; applied as a gain on PCONTROL or ALPHA with the trial's tracking "
       "error, the defaults hattr's choices",
       false,
       {{"base", "", 0.0, 0.0, 1.0, "the guidance whose strength adapts", {"pcontrol", "alpha"}},
        {"start_gain", "1", 1.0, 0.0, 1.0, "share of the guidance in the first guided trial"},
        {"forgetting", "1", 0.9, 0.0, 1.0, "share of the gain kept from one trial to the next"},
        {"error_gain_per_mm", "1/mm", 0.05, 0.0, 10.0, "gain added per millimetre of tracking error"},
        {"deadband_mm", "mm", 0.5, 0.0, 20.0, "tracking error ignored as the trainee's own variability"}}},
      {M::kPartialThenFull, "Channel first, then guided path",
       "Only a channel around the path corrects the pen in the first trials (partial guidance); then the "
       "guided path leads it (full guidance).",
       "partial then full haptic guidance (Teranishi et al. 2017, 2018): partial guidance is hattr's CHANNEL, "
       "full guidance PCONTROL, each with its own parameters; the switch is hattr's choice",
       false, {{"partial_trials", "trials", 5.0, 0.0, 1000.0, "guided trials with the channel before the full guidance"}}},
  };
}

/// Where a parameter lives in a configuration, and its unit's size in SI (a choice: the mode
/// or the fading schedule it selects).
struct Binding {
  double* value = nullptr;
  double si_per_unit = 1.0;
  TrainingMode* base = nullptr;
  FadingConfig::By* by = nullptr;
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
  if (is(M::kFading, "base")) return {.base = &c.fading.base};
  if (is(M::kFading, "by")) return {.by = &c.fading.by};
  if (is(M::kFading, "start_gain")) return {&c.fading.start_gain, 1.0};
  if (is(M::kFading, "end_gain")) return {&c.fading.end_gain, 1.0};
  if (is(M::kFading, "trials")) return {&c.fading.trials, 1.0};
  if (is(M::kFading, "step")) return {&c.fading.step, 1.0};
  if (is(M::kFading, "threshold_mm")) return {&c.fading.threshold_m, kMm};
  if (is(M::kAssistAsNeeded, "base")) return {.base = &c.assist.base};
  if (is(M::kAssistAsNeeded, "start_gain")) return {&c.assist.start_gain, 1.0};
  if (is(M::kAssistAsNeeded, "forgetting")) return {&c.assist.forgetting, 1.0};
  if (is(M::kAssistAsNeeded, "error_gain_per_mm")) return {&c.assist.error_gain_per_m, kPerMm};
  if (is(M::kAssistAsNeeded, "deadband_mm")) return {&c.assist.deadband_m, kMm};
  if (is(M::kPartialThenFull, "partial_trials")) return {&c.partial_then_full.partial_trials, 1.0};
  return {};
}

/// " mm" after a number in a message; nothing for a ratio ("1").
std::string unitSuffix(const StrategyParameter& p) {
  return p.unit.empty() || p.unit == "1" ? std::string() : fmt::format(" {}", p.unit);
}

std::string lowerCase(std::string_view text) {
  std::string lower(text);
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  return lower;
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
  const Binding b = bind(config, mode, name);
  HATTR_DEMAND(b.value || b.base || b.by, "strategy parameter {} {} has no place in GuidanceConfig", modeName(mode), name);
  if (!p.choices.empty()) {
    const bool index = value >= 0.0 && value < static_cast<double>(p.choices.size()) && value == std::floor(value);
    HATTR_THROW_UNLESS(index, "{} {}: expected one of {}, got {}", modeName(mode), name, fmt::join(p.choices, ", "), value);
    const auto i = static_cast<std::size_t>(value);
    if (b.base) *b.base = parseMode(p.choices[i]);
    if (b.by) *b.by = static_cast<FadingConfig::By>(i);
    return;
  }
  HATTR_THROW_UNLESS(std::isfinite(value) && value >= p.min && value <= p.max,
                     "{} {}: expected {} to {}{}, got {}", modeName(mode), name, p.min, p.max, unitSuffix(p), value);
  *b.value = value * b.si_per_unit;
}

void setStrategyParameter(GuidanceConfig& config, TrainingMode mode, std::string_view name, std::string_view value) {
  const StrategyParameter& p = findParameter(mode, name);
  // A choice by its name.
  if (!p.choices.empty()) {
    for (std::size_t i = 0; i < p.choices.size(); ++i) {
      if (p.choices[i] == lowerCase(value)) {
        setStrategyParameter(config, mode, name, static_cast<double>(i));
        return;
      }
    }
    throw InputError(fmt::format("{} {}: expected one of {}, got \"{}\"", modeName(mode), name,
                                 fmt::join(p.choices, ", "), value));
  }
  // A number, whole ("+0.25" too; one too large for a double is infinite, refused by the range).
  std::string_view number = value;
  if (number.starts_with('+')) number.remove_prefix(1);
  double parsed = 0.0;
  const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), parsed);
  const bool whole = !number.empty() && end == number.data() + number.size();
  HATTR_THROW_UNLESS(whole && (ec == std::errc() || ec == std::errc::result_out_of_range),
                     "{} {}: expected a number from {} to {}{}, got \"{}\"", modeName(mode), name, p.min, p.max,
                     unitSuffix(p), value);
  if (ec == std::errc::result_out_of_range) parsed = number.starts_with('-') ? -INFINITY : INFINITY;
  setStrategyParameter(config, mode, name, parsed);
}

StrategySetting parseStrategySetting(std::string_view text) {
  const auto equals = text.find('=');
  HATTR_THROW_UNLESS(equals != std::string_view::npos && equals > 0 && equals + 1 < text.size(),
                     "--param \"{}\": expected KEY=VALUE (e.g. half_width_mm=1.5, base=alpha)", text);
  return {std::string(text.substr(0, equals)), std::string(text.substr(equals + 1))};
}

void setStrategyParameters(GuidanceConfig& config, TrainingMode mode, std::span<const StrategySetting> settings) {
  std::set<std::string_view> seen;
  for (const auto& [name, value] : settings) {
    HATTR_THROW_UNLESS(seen.insert(name).second, "{} {}: given twice", modeName(mode), name);
    setStrategyParameter(config, mode, name, value);
  }
}

double strategyParameter(const GuidanceConfig& config, TrainingMode mode, std::string_view name) {
  const StrategyParameter& p = findParameter(mode, name);
  GuidanceConfig copy = config;
  const Binding b = bind(copy, mode, name);
  HATTR_DEMAND(b.value || b.base || b.by, "strategy parameter {} {} has no place in GuidanceConfig", modeName(mode), name);
  if (b.by) return static_cast<double>(static_cast<int>(*b.by));
  if (b.base) {
    for (std::size_t i = 0; i < p.choices.size(); ++i) {
      if (parseMode(p.choices[i]) == *b.base) return static_cast<double>(i);
    }
    throw Error(fmt::format("{} {}: {} is none of its choices", modeName(mode), name, modeName(*b.base)));
  }
  return *b.value / b.si_per_unit;
}

std::string strategyParameterText(const GuidanceConfig& config, TrainingMode mode, std::string_view name) {
  const StrategyParameter& p = findParameter(mode, name);
  const double value = strategyParameter(config, mode, name);
  // 12 digits: the unit's conversion (mm to m and back) leaves no 1.4999999999999998.
  if (p.choices.empty()) return fmt::format("{:.12g}", value);
  return std::string(p.choices.at(static_cast<std::size_t>(value)));
}

}  // namespace hattr::guidance
