#include "hattr/sim/trainee_model.hpp"

#include "hattr/core/text_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/sim/data_dir.hpp"
#include "random_internal.hpp"

namespace hattr::sim {
namespace {

using nlohmann::json;

constexpr unsigned bitOf(LearningHypothesis h) { return 1U << static_cast<unsigned>(h); }
constexpr unsigned kEveryHypothesis = 0b111;

/// What the model can use of each parameter: its unit in the file, the widest range the code
/// accepts, the factor to SI, and whether it is structural (the same for every subject).
struct ParameterSpec {
  const char* key;
  const char* unit;
  double hard_min;
  double hard_max;
  double to_si;
  bool structural;
  ModelParameter TraineeModel::*member;
  unsigned hypotheses = kEveryHypothesis;  ///< the hypotheses whose files state it (bits)
};

constexpr std::array kSpecs{
    ParameterSpec{"basis_count", "1", 2.0, 1000.0, 1.0, true, &TraineeModel::basis_count},
    ParameterSpec{"basis_width_ratio", "1", 0.05, 10.0, 1.0, true, &TraineeModel::basis_width_ratio},
    ParameterSpec{"projection_ridge", "1", 0.0, 1.0, 1.0, true, &TraineeModel::projection_ridge},
    ParameterSpec{"fast_retention", "1", 0.0, 1.0, 1.0, false, &TraineeModel::fast_retention},
    ParameterSpec{"fast_rate", "1", 0.0, 1.0, 1.0, false, &TraineeModel::fast_rate},
    ParameterSpec{"slow_retention", "1", 0.0, 1.0, 1.0, false, &TraineeModel::slow_retention},
    ParameterSpec{"slow_rate", "1", 0.0, 1.0, 1.0, false, &TraineeModel::slow_rate},
    ParameterSpec{"weber_fraction", "1", 0.0, 1.0, 1.0, false, &TraineeModel::weber_fraction},
    ParameterSpec{"felt_force_stiffness_N_per_m", "N_per_m", 1.0, 1e5, 1.0, false,
                  &TraineeModel::felt_force_stiffness_N_per_m},
    ParameterSpec{"position_noise_coefficient", "1", 0.0, 1.0, 1.0, false, &TraineeModel::position_noise_coefficient},
    ParameterSpec{"force_noise_coefficient", "1", 0.0, 1.0, 1.0, false, &TraineeModel::force_noise_coefficient},
    ParameterSpec{"deviation_rms_mm", "mm", 0.0, 20.0, units::kMetresPerMillimetre, false,
                  &TraineeModel::deviation_rms_m},
    ParameterSpec{"force_scale", "1", 0.0, 5.0, 1.0, false, &TraineeModel::force_scale},
    ParameterSpec{"force_offset_N", "N", -2.0, 2.0, 1.0, false, &TraineeModel::force_offset_N},
    ParameterSpec{"pace_cv", "1", 0.0, 0.5, 1.0, false, &TraineeModel::pace_cv},
    ParameterSpec{"grip_ratio", "1", 0.05, 1.0, 1.0, false, &TraineeModel::grip_ratio,
                  bitOf(LearningHypothesis::kForcePlan)},
    ParameterSpec{"plan_friction", "1", 0.0, 2.0, 1.0, false, &TraineeModel::plan_friction,
                  bitOf(LearningHypothesis::kForcePlan)},
    ParameterSpec{"guidance_dependence", "1", 0.0, 1.0, 1.0, false, &TraineeModel::guidance_dependence,
                  bitOf(LearningHypothesis::kGuidanceDependent)},
    ParameterSpec{"guidance_felt_N", "N", 0.0, 10.0, 1.0, false, &TraineeModel::guidance_felt_N,
                  bitOf(LearningHypothesis::kGuidanceDependent)},
};

constexpr std::array kHypothesisNames{"position-plan", "force-plan", "guidance-dependent"};

constexpr std::array kModelTopKeys{"format", "version", "hypothesis", "description", "units_note", "per_subject_note", "parameters"};
constexpr std::array kParameterKeys{"value", "unit", "range", "source", "per_subject", "note"};

std::string shown(const json* value) { return value ? jsonExcerpt(*value) : std::string("nothing"); }

const json* find(const json& object, const char* key) {
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

bool isFiniteNumber(const json* value) { return value && value->is_number() && std::isfinite(value->get<double>()); }

/// A source names a work with its year ("Smith ... 2006, ...") or says "assumption: <reason>".
bool isSource(const std::string& text) {
  constexpr std::string_view kAssumption = "assumption:";
  if (text.starts_with(kAssumption)) {
    return std::any_of(text.begin() + static_cast<std::ptrdiff_t>(kAssumption.size()), text.end(),
                       [](char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; });
  }
  for (std::size_t i = 0; i + 4 <= text.size(); ++i) {
    const bool digits = std::all_of(text.begin() + static_cast<std::ptrdiff_t>(i),
                                    text.begin() + static_cast<std::ptrdiff_t>(i + 4),
                                    [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; });
    if (digits && (text.compare(i, 2, "19") == 0 || text.compare(i, 2, "20") == 0)) return true;
  }
  return false;
}

/// A parameter's per_subject object: its distribution, and its kind as written (for messages).
std::pair<SubjectDistribution, std::string> parseSubjectDistribution(const json& item, const std::string& where) {
  const json* per_subject = find(item, "per_subject");
  HATTR_THROW_UNLESS(per_subject && per_subject->is_object(),
                     "{}.per_subject: expected an object {{\"kind\": ...}}, got {}", where, shown(per_subject));
  const json* kind = find(*per_subject, "kind");
  const std::string kind_text = kind && kind->is_string() ? kind->get<std::string>() : std::string();
  SubjectDistribution d;
  const char* spread_key = nullptr;
  if (kind_text == "fixed") {
    d.kind = SubjectDistribution::Kind::kFixed;
  } else if (kind_text == "normal") {
    d.kind = SubjectDistribution::Kind::kNormal;
    spread_key = "sd";
  } else if (kind_text == "lognormal") {
    d.kind = SubjectDistribution::Kind::kLogNormal;
    spread_key = "sigma_log";
  } else if (kind_text == "lognormal_complement") {
    d.kind = SubjectDistribution::Kind::kLogNormalComplement;
    spread_key = "sigma_log";
  } else {
    throw InputError(fmt::format("{}.per_subject.kind: expected one of fixed, normal, lognormal, "
                                 "lognormal_complement, got {}",
                                 where, shown(kind)));
  }
  for (const auto& field : per_subject->items()) {
    HATTR_THROW_UNLESS(field.key() == "kind" || (spread_key && field.key() == spread_key),
                       "{}.per_subject: unknown field \"{}\" for kind {}: expected {}", where, field.key(), kind_text,
                       spread_key ? fmt::format("kind, {}", spread_key) : std::string("kind"));
  }
  if (spread_key) {
    const json* spread = find(*per_subject, spread_key);
    HATTR_THROW_UNLESS(isFiniteNumber(spread) && spread->get<double>() >= 0.0 && spread->get<double>() <= 10.0,
                       "{}.per_subject.{}: expected a number in [0, 10], got {}", where, spread_key, shown(spread));
    d.spread = spread->get<double>();
  }
  return {d, kind_text};
}

ModelParameter parseParameter(const json& item, const ParameterSpec& spec, std::string_view source) {
  const std::string where = fmt::format("{}: parameters.{}", source, spec.key);
  HATTR_THROW_UNLESS(item.is_object(), "{}: expected an object with value, unit, range, source, per_subject, got {}",
                     where, jsonExcerpt(item));
  for (const auto& field : item.items()) {
    const bool known = std::any_of(kParameterKeys.begin(), kParameterKeys.end(),
                                   [&](const char* k) { return field.key() == k; });
    HATTR_THROW_UNLESS(known, "{}: unknown field \"{}\": expected one of {}", where, field.key(), fmt::join(kParameterKeys, ", "));
  }
  ModelParameter p;
  p.key = spec.key;

  const json* unit = find(item, "unit");
  HATTR_THROW_UNLESS(unit && unit->is_string() && *unit == spec.unit, "{}.unit: expected \"{}\", got {}", where,
                     spec.unit, shown(unit));

  const json* range = find(item, "range");
  const bool range_ok = range && range->is_array() && range->size() == 2 && isFiniteNumber(&(*range)[0]) &&
                        isFiniteNumber(&(*range)[1]) && (*range)[0].get<double>() <= (*range)[1].get<double>() &&
                        (*range)[0].get<double>() >= spec.hard_min && (*range)[1].get<double>() <= spec.hard_max;
  HATTR_THROW_UNLESS(range_ok, "{}.range: expected [min, max] with {} <= min <= max <= {} {}, got {}", where,
                     spec.hard_min / spec.to_si, spec.hard_max / spec.to_si, spec.unit, shown(range));
  const double lo = (*range)[0].get<double>();
  const double hi = (*range)[1].get<double>();

  const json* value = find(item, "value");
  HATTR_THROW_UNLESS(isFiniteNumber(value) && value->get<double>() >= lo && value->get<double>() <= hi,
                     "{}.value: expected a number in the range [{}, {}] {}, got {}", where, lo, hi, spec.unit,
                     shown(value));
  const double v = value->get<double>();
  HATTR_THROW_UNLESS(std::string_view(spec.key) != "basis_count" || v == std::floor(v),
                     "{}.value: expected an integer, got {}", where, jsonExcerpt(*value));

  const json* text = find(item, "source");
  HATTR_THROW_UNLESS(text && text->is_string() && isSource(text->get<std::string>()),
                     "{}.source: expected \"Author year, short title\" or \"assumption: <reason>\", got {}", where,
                     shown(text));

  const auto [d_read, kind_text] = parseSubjectDistribution(item, where);
  SubjectDistribution d = d_read;
  HATTR_THROW_UNLESS(!spec.structural || d.kind == SubjectDistribution::Kind::kFixed,
                     "{}.per_subject.kind: expected fixed (the basis is the same for every subject), got \"{}\"", where,
                     kind_text);
  HATTR_THROW_UNLESS(d.kind != SubjectDistribution::Kind::kLogNormal || v > 0.0,
                     "{}.value: expected a positive value for a lognormal distribution, got {}", where, v);
  HATTR_THROW_UNLESS(d.kind != SubjectDistribution::Kind::kLogNormalComplement || v < 1.0,
                     "{}.value: expected a value below 1 for a lognormal_complement distribution, got {}", where, v);

  p.value = v * spec.to_si;
  p.min = lo * spec.to_si;
  p.max = hi * spec.to_si;
  p.source = text->get<std::string>();
  d.spread *= d.kind == SubjectDistribution::Kind::kNormal ? spec.to_si : 1.0;
  p.per_subject = d;
  return p;
}

/// One subject's value of `p` from a standard normal draw `z` (not yet checked against the range).
double subjectValue(const ModelParameter& p, double z) {
  const double s = p.per_subject.spread;
  switch (p.per_subject.kind) {
    case SubjectDistribution::Kind::kFixed: return p.value;
    case SubjectDistribution::Kind::kNormal: return p.value + s * z;
    case SubjectDistribution::Kind::kLogNormal: return p.value * std::exp(s * z);
    case SubjectDistribution::Kind::kLogNormalComplement: return 1.0 - (1.0 - p.value) * std::exp(s * z);
  }
  return p.value;
}

double drawValue(const ModelParameter& p, detail::NormalSource& normal) {
  for (int attempt = 0; attempt < 10'000; ++attempt) {
    const double x = subjectValue(p, normal.normal());  // a draw even when fixed: streams stay aligned
    if (x >= p.min && x <= p.max) return x;
  }
  throw InvariantError(fmt::format("parameter {}: no draw in [{}, {}] after 10000 attempts", p.key, p.min, p.max));
}

}  // namespace

TraineeModel parseTraineeModel(std::string_view json_text, std::string_view source) {
  const json root = parseJsonObject(json_text, source);
  for (const auto& item : root.items()) {
    const bool known = std::any_of(kModelTopKeys.begin(), kModelTopKeys.end(), [&](const char* k) { return item.key() == k; });
    HATTR_THROW_UNLESS(known, "{}: unknown key \"{}\": expected one of {}", source, item.key(), fmt::join(kModelTopKeys, ", "));
  }
  const json* format = find(root, "format");
  HATTR_THROW_UNLESS(format && format->is_string() && *format == "hattr-trainee-model",
                     "{}: key format: expected \"hattr-trainee-model\", got {}", source, shown(format));
  const json* version = find(root, "version");
  HATTR_THROW_UNLESS(version && version->is_number_integer() && *version == 1, "{}: key version: expected 1, got {}",
                     source, shown(version));
  const json* parameters = find(root, "parameters");
  HATTR_THROW_UNLESS(parameters && parameters->is_object(), "{}: key parameters: expected an object, got {}", source,
                     shown(parameters));

  TraineeModel model;
  model.source_name = std::string(source);
  if (const json* hypothesis = find(root, "hypothesis")) {
    HATTR_THROW_UNLESS(hypothesis->is_string(), "{}: key hypothesis: expected one of {}, got {}", source,
                       fmt::join(kHypothesisNames, ", "), jsonExcerpt(*hypothesis));
    model.hypothesis = parseHypothesis(hypothesis->get<std::string>(), fmt::format("{}: key hypothesis", source));
  }
  const std::string_view hypothesis_name = hypothesisName(model.hypothesis);
  // The hypothesis's parameters, every one stated; no other's.
  std::vector<std::string> names;
  for (const auto& spec : kSpecs) {
    if ((spec.hypotheses & bitOf(model.hypothesis)) != 0) names.emplace_back(spec.key);
  }
  for (const auto& item : parameters->items()) {
    HATTR_THROW_UNLESS(std::find(names.begin(), names.end(), item.key()) != names.end(),
                       "{}: unknown parameter \"parameters.{}\" for the {} hypothesis: expected one of {}", source,
                       item.key(), hypothesis_name, fmt::join(names, ", "));
  }
  for (const auto& spec : kSpecs) {
    if ((spec.hypotheses & bitOf(model.hypothesis)) == 0) continue;
    const json* item = find(*parameters, spec.key);
    HATTR_THROW_UNLESS(item != nullptr, "{}: parameters.{}: missing (every parameter of the {} hypothesis must be stated)",
                       source, spec.key, hypothesis_name);
    model.*spec.member = parseParameter(*item, spec, source);
  }
  HATTR_THROW_UNLESS(model.fast_retention.value <= model.slow_retention.value,
                     "{}: parameters.fast_retention: expected at most slow_retention = {}, got {}", source,
                     model.slow_retention.value, model.fast_retention.value);
  HATTR_THROW_UNLESS(model.fast_rate.value >= model.slow_rate.value,
                     "{}: parameters.fast_rate: expected at least slow_rate = {}, got {}", source, model.slow_rate.value,
                     model.fast_rate.value);
  return model;
}

TraineeModel loadTraineeModel(const std::filesystem::path& file) {
  return parseTraineeModel(readTextFile(file), file.string());
}

std::string_view hypothesisName(LearningHypothesis hypothesis) {
  return kHypothesisNames.at(static_cast<std::size_t>(hypothesis));
}

LearningHypothesis parseHypothesis(std::string_view name, std::string_view where) {
  for (const LearningHypothesis h : allHypotheses()) {
    if (hypothesisName(h) == name) return h;
  }
  throw InputError(fmt::format("{}: expected one of {}, got \"{}\"", where, fmt::join(kHypothesisNames, ", "), name));
}

const std::vector<LearningHypothesis>& allHypotheses() {
  static const std::vector<LearningHypothesis> all{LearningHypothesis::kPositionPlan, LearningHypothesis::kForcePlan,
                                                   LearningHypothesis::kGuidanceDependent};
  return all;
}

std::filesystem::path hypothesisModelFile(LearningHypothesis hypothesis) {
  if (hypothesis == LearningHypothesis::kPositionPlan) return defaultDataDir() / "sim" / "trainee_model.json";
  return defaultDataDir() / "sim" / "hypotheses" / (std::string(hypothesisName(hypothesis)) + ".json");
}

TraineeModel loadHypothesisModel(LearningHypothesis hypothesis) {
  TraineeModel model = loadTraineeModel(hypothesisModelFile(hypothesis));
  HATTR_THROW_UNLESS(model.hypothesis == hypothesis, "{}: key hypothesis: expected \"{}\", got \"{}\"",
                     model.source_name, hypothesisName(hypothesis), hypothesisName(model.hypothesis));
  return model;
}

SubjectTraits populationTraits(const TraineeModel& m) {
  return {.fast_retention = m.fast_retention.value,
          .fast_rate = m.fast_rate.value,
          .slow_retention = m.slow_retention.value,
          .slow_rate = m.slow_rate.value,
          .weber_fraction = m.weber_fraction.value,
          .felt_force_stiffness_N_per_m = m.felt_force_stiffness_N_per_m.value,
          .position_noise_coefficient = m.position_noise_coefficient.value,
          .force_noise_coefficient = m.force_noise_coefficient.value,
          .deviation_rms_m = m.deviation_rms_m.value,
          .force_scale = m.force_scale.value,
          .force_offset_N = m.force_offset_N.value,
          .pace_cv = m.pace_cv.value,
          .grip_ratio = m.grip_ratio.value,
          .plan_friction = m.plan_friction.value,
          .guidance_dependence = m.guidance_dependence.value,
          .guidance_felt_N = m.guidance_felt_N.value};
}

SubjectTraits drawSubject(const TraineeModel& m, std::uint64_t seed) {
  constexpr std::uint64_t kSubjectStream = 0x5375626A65637473ULL;  // "Subjects"
  detail::NormalSource normal(detail::streamSeed(seed, kSubjectStream));
  SubjectTraits t;
  // The learning processes, drawn again together until the fast one stays the fast one.
  for (int attempt = 0;; ++attempt) {
    HATTR_DEMAND(attempt < 10'000, "no draw of the learning rates keeps A_f <= A_s and B_f >= B_s");
    t.fast_retention = drawValue(m.fast_retention, normal);
    t.fast_rate = drawValue(m.fast_rate, normal);
    t.slow_retention = drawValue(m.slow_retention, normal);
    t.slow_rate = drawValue(m.slow_rate, normal);
    if (t.fast_retention <= t.slow_retention && t.fast_rate >= t.slow_rate) break;
  }
  t.weber_fraction = drawValue(m.weber_fraction, normal);
  t.felt_force_stiffness_N_per_m = drawValue(m.felt_force_stiffness_N_per_m, normal);
  t.position_noise_coefficient = drawValue(m.position_noise_coefficient, normal);
  t.force_noise_coefficient = drawValue(m.force_noise_coefficient, normal);
  t.deviation_rms_m = drawValue(m.deviation_rms_m, normal);
  t.force_scale = drawValue(m.force_scale, normal);
  t.force_offset_N = drawValue(m.force_offset_N, normal);
  t.pace_cv = drawValue(m.pace_cv, normal);  // drawn after the others: they keep their draws
  // The hypotheses' own traits, last, so that every hypothesis draws the same subjects above.
  t.grip_ratio = drawValue(m.grip_ratio, normal);
  t.plan_friction = drawValue(m.plan_friction, normal);
  t.guidance_dependence = drawValue(m.guidance_dependence, normal);
  t.guidance_felt_N = drawValue(m.guidance_felt_N, normal);
  return t;
}

void validateTraits(const SubjectTraits& t) {
  const auto check = [](double value, double lo, double hi, const char* name) {
    HATTR_THROW_UNLESS(std::isfinite(value) && value >= lo && value <= hi,
                       "subject traits: {}: expected a number in [{}, {}], got {}", name, lo, hi, value);
  };
  check(t.fast_retention, 0.0, 1.0, "fast_retention");
  check(t.fast_rate, 0.0, 1.0, "fast_rate");
  check(t.slow_retention, 0.0, 1.0, "slow_retention");
  check(t.slow_rate, 0.0, 1.0, "slow_rate");
  check(t.weber_fraction, 0.0, 1.0, "weber_fraction");
  check(t.felt_force_stiffness_N_per_m, 1.0, 1e5, "felt_force_stiffness_N_per_m");
  check(t.position_noise_coefficient, 0.0, 1.0, "position_noise_coefficient");
  check(t.force_noise_coefficient, 0.0, 1.0, "force_noise_coefficient");
  check(t.deviation_rms_m, 0.0, 0.02, "deviation_rms_m");
  check(t.force_scale, 0.0, 5.0, "force_scale");
  check(t.force_offset_N, -2.0, 2.0, "force_offset_N");
  check(t.pace_cv, 0.0, 0.5, "pace_cv");
  check(t.grip_ratio, 0.05, 1.0, "grip_ratio");
  check(t.plan_friction, 0.0, 2.0, "plan_friction");
  check(t.guidance_dependence, 0.0, 1.0, "guidance_dependence");
  check(t.guidance_felt_N, 0.0, 10.0, "guidance_felt_N");
  HATTR_THROW_UNLESS(t.fast_retention <= t.slow_retention,
                     "subject traits: fast_retention: expected at most slow_retention = {}, got {}", t.slow_retention,
                     t.fast_retention);
  HATTR_THROW_UNLESS(t.fast_rate >= t.slow_rate, "subject traits: fast_rate: expected at least slow_rate = {}, got {}",
                     t.slow_rate, t.fast_rate);
}

}  // namespace hattr::sim
