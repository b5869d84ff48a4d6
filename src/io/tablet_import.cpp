#include "hattr/io/tablet_import.hpp"

#include "hattr/core/text_file.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "text_reader_internal.hpp"

namespace hattr::io {
namespace {

using detail::LineReader;
using detail::quotedField;

/// One tablet point in raw units, before calibration.
struct RawPoint {
  double x = 0, y = 0, t = 0;
  double pressure = 0;
  double azimuth = 0, altitude = 0;
  bool button_down = false;
  bool lift_after = false;  ///< the pen left the paper after this point (the format says so)
};

/// Makes time stamps strictly increasing without dropping a point: a run of stamps that
/// do not exceed the previous one is spread evenly up to the next larger stamp (or by one
/// time unit each at the end). Returns how many stamps changed.
std::size_t retimeNonIncreasing(std::vector<RawPoint>& points, double unit) {
  std::size_t changed = 0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    const double prev = points[i - 1].t;
    if (points[i].t > prev) continue;
    std::size_t j = i;
    while (j < points.size() && points[j].t <= prev) ++j;
    const double next = j < points.size() ? points[j].t : prev + unit * static_cast<double>(j - i + 1);
    const double step = (next - prev) / static_cast<double>(j - i + 1);
    for (std::size_t k = i; k < j; ++k) points[k].t = prev + step * static_cast<double>(k - i + 1);
    changed += j - i;
    i = j - 1;
  }
  return changed;
}

/// The nominal rate [Hz]: one over the median time step of the re-timed stamps (0 for one point).
double medianRate_hz(const std::vector<Sample>& samples) {
  std::vector<double> steps;
  for (std::size_t i = 1; i < samples.size(); ++i) steps.push_back(samples[i].t_s - samples[i - 1].t_s);
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  return std::round(1.0 / steps[steps.size() / 2]);
}

/// A tablet that reports nothing while the pen is in the air leaves each lift as a gap between
/// two pen-down points. Each lift the format marks between two pen-down points gets one pen-up
/// sample: where the pen left the paper (its path in the air is not recorded), one sample
/// period later (or half-way to the next point, if sooner), with no force, no pressure and the
/// tilt it left with. Velocities are differenced within each stroke, never across a lift (the
/// marks are still). How many were inserted is in metadata `inserted_lift_samples`.
std::vector<Sample> withLiftsMarked(std::vector<Sample> samples, const std::vector<bool>& lift_after, double rate_hz,
                                    ProfileMetadata& meta) {
  std::vector<Sample> out;
  out.reserve(samples.size() + static_cast<std::size_t>(std::count(lift_after.begin(), lift_after.end(), true)));
  std::size_t stroke_begin = 0;
  std::size_t inserted = 0;
  const double period_s = rate_hz > 0.0 ? 1.0 / rate_hz : 0.0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    out.push_back(samples[i]);
    const bool marks = lift_after[i] && i + 1 < samples.size() && samples[i].pen_down && samples[i + 1].pen_down;
    if (!marks) continue;
    fillVelocityByFiniteDifferences(std::span(out).subspan(stroke_begin));
    Sample up = samples[i];
    up.t_s = samples[i].t_s + std::min(period_s, 0.5 * (samples[i + 1].t_s - samples[i].t_s));
    up.v_WT.setZero();
    up.f_user_W.setZero();
    up.pen_down = false;
    up.in_contact = false;
    up.pressure_raw = 0.0;
    out.push_back(up);
    stroke_begin = out.size();
    ++inserted;
  }
  fillVelocityByFiniteDifferences(std::span(out).subspan(stroke_begin));
  meta.extra["inserted_lift_samples"] = fmt::format("{}", inserted);
  return out;
}

/// Calibrated SI profile from raw points.
HapticProfile toProfile(std::vector<RawPoint> points, const TabletCalibration& cal, bool has_tilt,
                        std::string source, std::string_view format_name) {
  ProfileMetadata meta;
  meta.source = std::move(source);
  meta.device = std::string(format_name) + " tablet";
  meta.created_utc = utcNowIso8601();
  meta.extra["calibration"] = cal.name;
  meta.extra["time_origin_s"] = fmt::format("{}", points.front().t * cal.time_s_per_unit);
  const std::size_t retimed = retimeNonIncreasing(points, 1.0);
  meta.extra["retimed_samples"] = fmt::format("{}", retimed);

  std::vector<Sample> samples;
  samples.reserve(points.size());
  const double t0 = points.front().t;
  const double y_sign = cal.y_axis_toward_writer ? -1.0 : 1.0;
  for (const RawPoint& p : points) {
    Sample& s = samples.emplace_back();
    s.t_s = (p.t - t0) * cal.time_s_per_unit;
    s.p_WT = Vec3(p.x * cal.metres_per_unit_x, y_sign * p.y * cal.metres_per_unit_y, 0.0);
    s.pen_down = p.button_down || p.pressure > cal.pen_down_pressure_raw;
    s.in_contact = s.pen_down;
    s.pressure_raw = p.pressure;
    const double azimuth = has_tilt ? p.azimuth * cal.angle_rad_per_unit : 0.0;
    const double altitude = has_tilt ? p.altitude * cal.angle_rad_per_unit : cal.default_altitude_rad;
    s.tilt_azimuth_rad = azimuth;
    s.tilt_altitude_rad = altitude;
    const double axial = s.pen_down ? pressureToNewtons(p.pressure, cal) : 0.0;
    s.f_user_W = has_tilt ? axialForceOnPaper(axial, azimuth, altitude)
                          : Vec3(0.0, 0.0, -axial * std::sin(altitude));
  }
  const double rate_hz = medianRate_hz(samples);
  meta.nominal_rate_hz = rate_hz;
  std::vector<bool> lift_after(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) lift_after[i] = points[i].lift_after;
  samples = withLiftsMarked(std::move(samples), lift_after, rate_hz, meta);
  if (cal.centre_on_paper) {
    const Vec3 shift = centreOnPaper(samples);
    meta.extra["placed_shift_m"] = fmt::format("{} {}", shift.x(), shift.y());
  }

  HapticProfile profile(std::move(meta), RawChannels{.pressure = true, .tilt = has_tilt});
  profile.reserve(samples.size());
  for (const auto& s : samples) profile.append(s);
  return profile;
}

double requireNumber(std::string_view field, std::string_view name, const LineReader& reader) {
  const auto value = detail::parseDouble(field);
  HATTR_THROW_UNLESS(value.has_value() && std::isfinite(*value), "{}: field {}: expected a number, got {}",
                     reader.where(), name, quotedField(field));
  return *value;
}

// ---- Calibration JSON -----------------------------------------------------------------

struct NumberField {
  std::string_view key;
  double TabletCalibration::*member;
  double min;
  double max;
};

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr NumberField kNumberFields[] = {
    {"metres_per_unit_x", &TabletCalibration::metres_per_unit_x, 1e-9, 1.0},
    {"metres_per_unit_y", &TabletCalibration::metres_per_unit_y, 1e-9, 1.0},
    {"pressure_max_raw", &TabletCalibration::pressure_max_raw, 1.0, 1e9},
    {"pressure_max_N", &TabletCalibration::pressure_max_N, 1e-3, 1e3},
    {"pressure_exponent", &TabletCalibration::pressure_exponent, 0.1, 10.0},
    {"pen_down_pressure_raw", &TabletCalibration::pen_down_pressure_raw, 0.0, 1e9},
    {"angle_rad_per_unit", &TabletCalibration::angle_rad_per_unit, 0.0, 1.0},
    {"default_altitude_rad", &TabletCalibration::default_altitude_rad, 0.0, std::numbers::pi / 2},
    {"time_s_per_unit", &TabletCalibration::time_s_per_unit, 1e-9, kInf},
};

}  // namespace

TabletCalibration svc2004Calibration() {
  TabletCalibration cal;
  cal.name = "svc2004 default (Wacom Intuos: 0.01 mm/unit, y up, 1023 = 1.75 N assumed, tilt 0.1 deg, centred)";
  cal.angle_rad_per_unit = units::degreesToRadians(0.1);
  return cal;
}

TabletCalibration susigCalibration() {
  TabletCalibration cal;
  cal.name = "susig default (0.01 mm/unit assumed, y up, pressure 0..255 = 0..1.75 N assumed, no tilt, centred)";
  cal.pressure_max_raw = 255.0;
  cal.angle_rad_per_unit = 0.0;
  return cal;
}

TabletCalibration parseCalibration(std::string_view json_text, std::string_view source_name,
                                   TabletCalibration cal) {
  const nlohmann::json json = parseJsonObject(json_text, source_name);
  for (const auto& item : json.items()) {
    const std::string& key = item.key();
    const nlohmann::json& value = item.value();
    if (key == "name") {
      HATTR_THROW_UNLESS(value.is_string(), "{}: key name: expected a string, got {}", source_name, jsonExcerpt(value));
      cal.name = value.get<std::string>();
      continue;
    }
    if (key == "y_axis_toward_writer" || key == "centre_on_paper") {
      HATTR_THROW_UNLESS(value.is_boolean(), "{}: key {}: expected true or false, got {}", source_name, key,
                         jsonExcerpt(value));
      (key == "centre_on_paper" ? cal.centre_on_paper : cal.y_axis_toward_writer) = value.get<bool>();
      continue;
    }
    const auto* field = std::find_if(std::begin(kNumberFields), std::end(kNumberFields),
                                     [&](const NumberField& f) { return f.key == key; });
    if (field == std::end(kNumberFields)) {
      std::string keys = "name, y_axis_toward_writer, centre_on_paper";
      for (const auto& f : kNumberFields) keys += fmt::format(", {}", f.key);
      throw InputError(fmt::format("{}: unknown key \"{}\": expected one of {}", source_name, key, keys));
    }
    HATTR_THROW_UNLESS(value.is_number(), "{}: key {}: expected a number in [{}, {}], got {}", source_name,
                       key, field->min, field->max, jsonExcerpt(value));
    const double number = value.get<double>();
    HATTR_THROW_UNLESS(number >= field->min && number <= field->max,
                       "{}: key {}: expected a number in [{}, {}], got {}", source_name, key, field->min,
                       field->max, number);
    cal.*(field->member) = number;
  }
  return cal;
}

TabletCalibration loadCalibration(const std::filesystem::path& file, TabletCalibration defaults) {
  return parseCalibration(readTextFile(file), file.string(), std::move(defaults));
}

double pressureToNewtons(double raw, const TabletCalibration& cal) {
  const double fraction = std::clamp(raw / cal.pressure_max_raw, 0.0, 1.0);
  return cal.pressure_max_N * std::pow(fraction, cal.pressure_exponent);
}

Vec3 axialForceOnPaper(double axial_N, double azimuth_rad, double altitude_rad) {
  // Unit vector from the tip toward the barrel; the pen pushes the paper the other way.
  const double horizontal = std::cos(altitude_rad);
  const Vec3 tip_to_barrel(horizontal * std::sin(azimuth_rad), horizontal * std::cos(azimuth_rad),
                           std::sin(altitude_rad));
  return -axial_N * tip_to_barrel;
}

// ---- SVC2004 --------------------------------------------------------------------------

namespace {

/// SVC2004's tablet reports nothing in the air, and the first point after the pen lands has
/// button 0: a lift precedes a point whose button is 0 and which follows the one before it by
/// more than 1.5 median time steps (a point the tablet dropped leaves such a gap too, but with
/// the button still 1). Read on the raw stamps, before any re-timing.
void markSvc2004Lifts(std::vector<RawPoint>& points, const std::vector<long long>& buttons) {
  std::vector<double> steps;
  for (std::size_t i = 1; i < points.size(); ++i) steps.push_back(points[i].t - points[i - 1].t);
  if (steps.empty()) return;
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
  const double step = steps[steps.size() / 2];
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (buttons[i] == 0 && points[i].t - points[i - 1].t > 1.5 * step) points[i - 1].lift_after = true;
  }
}

}  // namespace

HapticProfile importSvc2004(std::istream& in, std::string_view source_name, const TabletCalibration& cal) {
  LineReader reader(in, std::string(source_name));
  std::string line;
  HATTR_THROW_UNLESS(reader.next(line), "{}: empty file: expected the number of points on line 1",
                     source_name);
  const auto count = detail::parseInteger(line);
  HATTR_THROW_UNLESS(count && *count > 0, "{}: expected the number of points (an integer > 0), got {}",
                     reader.where(), quotedField(line));

  constexpr std::string_view kFields[] = {"X", "Y", "T", "button", "azimuth", "altitude", "pressure"};
  std::vector<RawPoint> points;
  std::vector<long long> raw_buttons;
  points.reserve(static_cast<std::size_t>(*count));
  while (reader.next(line)) {
    if (detail::trim(line).empty()) continue;
    const auto fields = detail::splitBlanks(line);
    HATTR_THROW_UNLESS(fields.size() == 7,
                       "{}: expected 7 fields (X Y T button azimuth altitude pressure), got {}",
                       reader.where(), fields.size());
    double v[7];
    for (std::size_t i = 0; i < 7; ++i) v[i] = requireNumber(fields[i], kFields[i], reader);
    points.push_back({.x = v[0], .y = v[1], .t = v[2], .pressure = v[6], .azimuth = v[4],
                      .altitude = v[5], .button_down = (static_cast<long long>(v[3]) & 1) != 0});
    raw_buttons.push_back(static_cast<long long>(v[3]));
  }
  HATTR_THROW_UNLESS(points.size() == static_cast<std::size_t>(*count),
                     "{}: line 1 announces {} points, the file has {}", source_name, *count, points.size());
  markSvc2004Lifts(points, raw_buttons);
  return toProfile(std::move(points), cal, true,
                   fmt::format("import:svc2004 {}", std::filesystem::path(source_name).filename().string()),
                   "svc2004");
}

HapticProfile importSvc2004(const std::filesystem::path& file, const TabletCalibration& cal) {
  std::ifstream in = detail::openInputFile(file);
  return importSvc2004(in, file.string(), cal);
}

// ---- SUSIG ----------------------------------------------------------------------------

HapticProfile importSusig(std::istream& in, std::string_view source_name, const TabletCalibration& cal) {
  LineReader reader(in, std::string(source_name));
  std::string line;
  std::optional<long long> data_size;
  std::vector<std::string> header;
  std::vector<RawPoint> points;
  std::size_t strokes = 0;
  const auto splitAny = [](std::string_view text) {
    std::string spaced(text);
    std::replace(spaced.begin(), spaced.end(), ',', ' ');
    std::vector<std::string> out;
    for (const auto f : detail::splitBlanks(spaced)) out.emplace_back(f);
    return out;
  };
  while (reader.next(line)) {
    const std::string_view text = detail::trim(line);
    if (text.empty()) continue;
    // "DataSize: N" and the column header may come in either order, before the data.
    if (text.starts_with("DataSize")) {
      const auto colon = text.find(':');
      data_size = colon == std::string_view::npos ? std::nullopt : detail::parseInteger(text.substr(colon + 1));
      HATTR_THROW_UNLESS(data_size && *data_size > 0, "{}: expected \"DataSize: N\" with N > 0, got {}",
                         reader.where(), quotedField(text));
      continue;
    }
    if (std::isalpha(static_cast<unsigned char>(text.front()))) {
      header = splitAny(text);
      const std::vector<std::string> expected{"X", "Y", "TStamp", "Pres.", "EndPts"};
      HATTR_THROW_UNLESS(header == expected, "{}: expected the header \"X, Y, TStamp, Pres., EndPts\", got {}",
                         reader.where(), quotedField(text));
      continue;
    }
    HATTR_THROW_UNLESS(!header.empty() && data_size, "{}: data before the header and DataSize lines",
                       reader.where());
    const auto fields = splitAny(text);
    HATTR_THROW_UNLESS(fields.size() == 5, "{}: expected 5 fields (X, Y, TStamp, Pres., EndPts), got {}",
                       reader.where(), fields.size());
    double v[5];
    for (std::size_t i = 0; i < 5; ++i) v[i] = requireNumber(fields[i], header[i], reader);
    HATTR_THROW_UNLESS(v[4] == 0.0 || v[4] == 1.0, "{}: field EndPts: expected 0 or 1, got {}", reader.where(),
                       quotedField(fields[4]));
    strokes += v[4] == 1.0 ? 1 : 0;
    points.push_back({.x = v[0], .y = v[1], .t = v[2], .pressure = v[3], .lift_after = v[4] == 1.0});
  }
  HATTR_THROW_UNLESS(data_size.has_value() && !header.empty(),
                     "{}: expected a \"DataSize: N\" line and the header \"X, Y, TStamp, Pres., EndPts\"",
                     source_name);
  HATTR_THROW_UNLESS(points.size() == static_cast<std::size_t>(*data_size),
                     "{}: DataSize announces {} points, the file has {}", source_name, *data_size, points.size());
  HapticProfile profile = toProfile(
      std::move(points), cal, false,
      fmt::format("import:susig {}", std::filesystem::path(source_name).filename().string()), "susig");
  profile.metadata().extra["strokes"] = fmt::format("{}", strokes);
  return profile;
}

HapticProfile importSusig(const std::filesystem::path& file, const TabletCalibration& cal) {
  std::ifstream in = detail::openInputFile(file);
  return importSusig(in, file.string(), cal);
}

}  // namespace hattr::io
