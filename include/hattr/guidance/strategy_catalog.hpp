#pragma once
/// Every training strategy hattr has, described for people and programs (`hattr strategies`,
/// the studio, Python): its name, a plain-language name for a teacher, what it does in one line,
/// its source, and its parameters with units, defaults and ranges. A parameter is set by its
/// name in the units shown (millimetres and the paper's N/mm at this edge, converted once) and
/// refused outside its range; a parameter with choices is set by a choice's name.
/// docs/training_modes.md has the same table with the reasoning.

#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hattr/guidance/training_guidance.hpp"

namespace hattr::guidance {

/// One parameter of a strategy, in the units people give it: a number in a range, or one of
/// a list of choices (then default_value, min and max are choice indices).
struct StrategyParameter {
  std::string_view name;         ///< "half_width_mm"
  std::string_view unit;         ///< "mm" ("" for a choice)
  double default_value = 0.0;    ///< in `unit`
  double min = 0.0;              ///< the range accepted, in `unit`
  double max = 0.0;
  std::string_view meaning;      ///< one line
  std::vector<std::string_view> choices = {};  ///< {"pcontrol", "alpha"}; empty: a number
};

struct StrategyInfo {
  TrainingMode mode;
  std::string_view plain_name;   ///< for a teacher: "Guided path"
  std::string_view description;  ///< one line
  std::string_view source;       ///< where the law comes from; what of it is hattr's choice
  bool mentored = false;         ///< a live expert guides (docs/mentoring.md)
  std::vector<StrategyParameter> parameters;
};

/// Every strategy, in TrainingMode order.
[[nodiscard]] const std::vector<StrategyInfo>& strategyCatalog();
[[nodiscard]] const StrategyInfo& strategyInfo(TrainingMode mode);

/// Sets `mode`'s parameter `name` to `value` (in the catalog's unit; a choice's index) in
/// `config`. Throws InputError naming the strategy's parameters for an unknown name, and the
/// parameter, its range with its unit and the value for one outside it.
void setStrategyParameter(GuidanceConfig& config, TrainingMode mode, std::string_view name, double value);
/// The same from text as people give it: a number, or for a parameter with choices a choice's
/// name (any case). A number too large for a double reads as infinite (then refused by its
/// range). InputError naming the parameter and what it expects otherwise.
void setStrategyParameter(GuidanceConfig& config, TrainingMode mode, std::string_view name, std::string_view value);

/// A parameter's name and its value as given (a number or a choice's name).
using StrategySetting = std::pair<std::string, std::string>;

/// One "KEY=VALUE" setting (`hattr train --param`); InputError for one that is not KEY=VALUE.
[[nodiscard]] StrategySetting parseStrategySetting(std::string_view text);

/// Each setting through setStrategyParameter; InputError for a name given twice.
void setStrategyParameters(GuidanceConfig& config, TrainingMode mode, std::span<const StrategySetting> settings);

/// A parameter's value in `config`, in the catalog's unit (a choice's index).
[[nodiscard]] double strategyParameter(const GuidanceConfig& config, TrainingMode mode, std::string_view name);
/// The same as people read it: the number with 12 significant digits, or the choice's name.
[[nodiscard]] std::string strategyParameterText(const GuidanceConfig& config, TrainingMode mode, std::string_view name);

}  // namespace hattr::guidance
