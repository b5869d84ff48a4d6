#include "hattr/io/profile_csv.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "text_reader_internal.hpp"

namespace hattr::io {
namespace {

using detail::LineReader;
using detail::quotedField;

// ---- Column units ----------------------------------------------------------------------

struct UnitScale {
  std::string_view unit;
  double to_si;
};

/// The units a channel's column may carry, SI first (the one the writer uses).
std::vector<UnitScale> acceptedUnits(Channel channel) {
  switch (channel) {
    case Channel::kTime: return {{"s", 1.0}, {"ms", units::kSecondsPerMillisecond}};
    case Channel::kX:
    case Channel::kY:
    case Channel::kZ: return {{"m", 1.0}, {"mm", units::kMetresPerMillimetre}};
    case Channel::kVx:
    case Channel::kVy:
    case Channel::kVz: return {{"m_per_s", 1.0}, {"mm_per_s", units::kMetresPerMillimetre}};
    case Channel::kAzimuth:
    case Channel::kAltitude: return {{"rad", 1.0}, {"deg", units::kRadiansPerDegree}};
    default: return {{channelInfo(channel).unit, 1.0}};
  }
}

std::string unitList(Channel channel) {
  std::string list;
  for (const auto& u : acceptedUnits(channel)) list += (list.empty() ? "" : ", ") + std::string(u.unit);
  return list;
}

bool isFlag(Channel channel) { return channel == Channel::kContact || channel == Channel::kPenDown; }

// ---- Column row ------------------------------------------------------------------------

struct Column {
  Channel channel;
  double to_si;
  std::string header;
};

constexpr std::array kRequired{Channel::kTime, Channel::kX,  Channel::kY,  Channel::kZ,
                               Channel::kFx,   Channel::kFy, Channel::kFz, Channel::kPenDown};

/// Finds the stored channel a column header names: the longest channel name followed by
/// '_' and a unit.
Column parseColumnHeader(std::string_view header, int index, const LineReader& reader) {
  const ChannelInfo* best = nullptr;
  for (const auto& info : allChannels()) {
    if (info.derived) continue;
    if (header.size() > info.name.size() + 1 && header.starts_with(info.name) &&
        header[info.name.size()] == '_' && (!best || info.name.size() > best->name.size())) {
      best = &info;
    }
  }
  if (!best) {
    std::string names;
    for (const auto& info : allChannels())
      if (!info.derived) names += (names.empty() ? "" : ", ") + std::string(info.name);
    throw InputError(fmt::format("{}: column {}: expected a channel name followed by _unit "
                                 "(channels: {}), got {}",
                                 reader.where(), index, names, quotedField(header)));
  }
  const std::string_view unit = header.substr(best->name.size() + 1);
  for (const auto& accepted : acceptedUnits(best->channel)) {
    if (accepted.unit == unit) return {best->channel, accepted.to_si, std::string(header)};
  }
  throw InputError(fmt::format("{}: column {} ({}): unknown unit for {}: expected one of {}, got {}",
                               reader.where(), index, header, best->name, unitList(best->channel),
                               quotedField(unit)));
}

std::vector<Column> parseColumnRow(std::string_view line, const LineReader& reader) {
  std::vector<Column> columns;
  std::set<Channel> seen;
  int index = 0;
  for (const auto field : detail::splitFields(line, ',')) {
    ++index;
    Column column = parseColumnHeader(detail::trim(field), index, reader);
    HATTR_THROW_UNLESS(seen.insert(column.channel).second,
                       "{}: column {} ({}): channel {} appears twice", reader.where(), index,
                       column.header, channelInfo(column.channel).name);
    columns.push_back(std::move(column));
  }
  std::string missing;
  for (const Channel required : kRequired) {
    if (!seen.contains(required))
      missing += (missing.empty() ? "" : ", ") + std::string(channelInfo(required).name);
  }
  HATTR_THROW_UNLESS(missing.empty(), "{}: missing required column(s): {} (got {})", reader.where(),
                     missing, quotedField(line));
  HATTR_THROW_UNLESS(seen.contains(Channel::kAzimuth) == seen.contains(Channel::kAltitude),
                     "{}: tilt needs both azimuth and altitude columns, got only one",
                     reader.where());
  return columns;
}

// ---- Sample fields ---------------------------------------------------------------------

/// What no pen on paper can produce: a value beyond this is a broken file (or an attack: a
/// reference with absurd positions would ask the guidance for absurd forces). Velocities are
/// not bounded: a file without them gets them by finite differences, which a tight time step
/// can make large from sane positions, and a file must read back as it was written.
struct PhysicalBound {
  double limit;
  std::string_view unit;
  std::string_view why;
};

PhysicalBound physicalBound(Channel channel) {
  switch (channel) {
    case Channel::kX: case Channel::kY: case Channel::kZ:
      return {1.0, "m", "a pen's workspace is well under a metre"};
    case Channel::kFx: case Channel::kFy: case Channel::kFz:
    case Channel::kCmdFx: case Channel::kCmdFy: case Channel::kCmdFz:
    case Channel::kGuideFx: case Channel::kGuideFy: case Channel::kGuideFz:
      return {1000.0, "N", "a hand on a pen exerts well under a kilonewton"};
    case Channel::kTime:
      return {1e7, "s", "a recording shorter than 115 days"};
    default:
      return {std::numeric_limits<double>::max(), "", ""};
  }
}

double parseValue(std::string_view field, const Column& column, int index, const LineReader& reader) {
  const auto where = [&] { return fmt::format("{}: column {} ({})", reader.where(), index, column.header); };
  const auto value = detail::parseDouble(field);
  HATTR_THROW_UNLESS(value.has_value(), "{}: expected a number, got {}", where(), quotedField(field));
  HATTR_THROW_UNLESS(std::isfinite(*value), "{}: expected a finite number, got {}", where(),
                     quotedField(detail::trim(field)));
  HATTR_THROW_UNLESS(!isFlag(column.channel) || *value == 0.0 || *value == 1.0,
                     "{}: expected 0 or 1, got {}", where(), quotedField(detail::trim(field)));
  const double si = *value * column.to_si;
  const PhysicalBound bound = physicalBound(column.channel);
  HATTR_THROW_UNLESS(std::abs(si) <= bound.limit, "{}: expected at most {} {} in magnitude ({}), got {}", where(),
                     bound.limit, bound.unit, bound.why, quotedField(detail::trim(field)));
  return si;
}

Sample parseRow(std::string_view line, const std::vector<Column>& columns, const LineReader& reader) {
  const auto fields = detail::splitFields(line, ',');
  HATTR_THROW_UNLESS(fields.size() == columns.size(), "{}: expected {} fields, got {}", reader.where(),
                     columns.size(), fields.size());
  Sample sample;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    setChannelValue(sample, columns[i].channel,
               parseValue(fields[i], columns[i], static_cast<int>(i) + 1, reader));
  }
  return sample;
}

// ---- Metadata --------------------------------------------------------------------------

bool isValidKey(std::string_view key) {
  return !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
  });
}

/// True if the text holds a control character (tab excepted): such metadata cannot be
/// written on one line and read back unchanged, so both reader and writer refuse it.
bool hasControlCharacter(std::string_view text) {
  return std::any_of(text.begin(), text.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return (u < 0x20 && c != '\t') || u == 0x7f;
  });
}

// Keys that describe the format itself and are not kept as metadata.
bool isFormatKey(std::string_view key) { return key == "format" || key == "units" || key == "frame"; }

void applyMetadata(ProfileMetadata& meta, std::string_view key, std::string_view value,
                   const LineReader& reader) {
  if (key == "format") {
    HATTR_THROW_UNLESS(value == kProfileFormat, "{}: format: expected \"{}\", got {}", reader.where(),
                       kProfileFormat, quotedField(value));
  } else if (key == "subject") {
    meta.subject = value;
  } else if (key == "skill") {
    meta.skill = value;
  } else if (key == "device") {
    meta.device = value;
  } else if (key == "source") {
    meta.source = value;
  } else if (key == "created_utc") {
    meta.created_utc = value;
  } else if (key == "rate_hz") {
    const auto rate = detail::parseDouble(value);
    HATTR_THROW_UNLESS(rate && std::isfinite(*rate) && *rate >= 0.0,
                       "{}: rate_hz: expected a finite number >= 0, got {}", reader.where(), quotedField(value));
    meta.nominal_rate_hz = *rate;
  } else if (!isFormatKey(key)) {
    meta.extra.emplace(key, value);
  }
}

/// Parses "# key: value"; a '#' line without "key:" is a comment and is skipped.
void parseMetadataLine(std::string_view line, ProfileMetadata& meta, std::set<std::string>& seen,
                       const LineReader& reader) {
  HATTR_THROW_UNLESS(!hasControlCharacter(line), "{}: expected printable metadata text, got a control character",
                     reader.where());
  const std::string_view body = detail::trim(line.substr(1));
  const auto colon = body.find(':');
  if (colon == std::string_view::npos) return;
  const std::string_view key = detail::trim(body.substr(0, colon));
  if (!isValidKey(key)) return;
  HATTR_THROW_UNLESS(seen.insert(std::string(key)).second, "{}: metadata key {} appears twice",
                     reader.where(), quotedField(key));
  applyMetadata(meta, key, detail::trim(body.substr(colon + 1)), reader);
}

// ---- Whole profile ---------------------------------------------------------------------

RawChannels rawChannelsOf(const std::vector<Column>& columns) {
  RawChannels raw;
  for (const auto& c : columns) {
    if (c.channel == Channel::kPressure) raw.pressure = true;
    if (c.channel == Channel::kAzimuth) raw.tilt = true;
  }
  return raw;
}

bool hasColumn(const std::vector<Column>& columns, Channel channel) {
  return std::any_of(columns.begin(), columns.end(), [&](const Column& c) { return c.channel == channel; });
}

}  // namespace

HapticProfile readProfileCsv(std::istream& in, std::string_view source_name) {
  LineReader reader(in, std::string(source_name));
  ProfileMetadata meta;
  std::set<std::string> seen_keys;
  std::string line;

  // Metadata lines, then the column row.
  bool have_line = false;
  while ((have_line = reader.next(line)) && (line.empty() || line.front() == '#')) {
    if (!line.empty()) parseMetadataLine(line, meta, seen_keys, reader);
  }
  HATTR_THROW_UNLESS(have_line || reader.lineNumber() > 0,
                     "{}: empty file: expected '# key: value' metadata lines, a column row and data",
                     source_name);
  HATTR_THROW_UNLESS(have_line, "{}:{}: expected a column row (t_s,x_m,...), got the end of the file",
                     source_name, reader.lineNumber());
  const std::vector<Column> columns = parseColumnRow(line, reader);

  // Data rows.
  HapticProfile profile(std::move(meta), rawChannelsOf(columns));
  std::vector<Sample> samples;
  const bool has_velocity = hasColumn(columns, Channel::kVx);
  const bool has_contact = hasColumn(columns, Channel::kContact);
  while (reader.next(line)) {
    if (line.empty()) {
      // Only trailing blank lines are allowed.
      std::string rest;
      while (reader.next(rest)) {
        HATTR_THROW_UNLESS(rest.empty(), "{}: expected a data row, got a blank line before it",
                           reader.where());
      }
      break;
    }
    Sample sample = parseRow(line, columns, reader);
    if (!has_contact) sample.in_contact = sample.pen_down;
    HATTR_THROW_UNLESS(samples.empty() || sample.t_s > samples.back().t_s,
                       "{}: column 1 ({}): time must increase strictly: expected > {}, got {}",
                       reader.where(), columns.front().header, samples.back().t_s, sample.t_s);
    samples.push_back(sample);
  }
  HATTR_THROW_UNLESS(!samples.empty(), "{}: no data rows after the column row", source_name);
  HATTR_THROW_UNLESS(hasColumn(columns, Channel::kVx) == hasColumn(columns, Channel::kVy) &&
                         hasColumn(columns, Channel::kVx) == hasColumn(columns, Channel::kVz),
                     "{}: velocity needs all of vx, vy, vz or none", source_name);
  if (!has_velocity) fillVelocityByFiniteDifferences(samples);
  profile.reserve(samples.size());
  for (const auto& s : samples) profile.append(s);
  return profile;
}

HapticProfile readProfileCsv(const std::filesystem::path& file) {
  std::ifstream in = detail::openInputFile(file);
  return readProfileCsv(in, file.string());
}

void writeProfileCsv(const HapticProfile& profile, std::ostream& out) {
  HATTR_THROW_UNLESS(!profile.empty(), "cannot write a profile with no samples");
  const ProfileMetadata& meta = profile.metadata();
  const RawChannels raw = profile.rawChannels();

  // Header: format, then the metadata, one "# key: value" line each.
  fmt::memory_buffer buf;
  const auto put = [&](std::string_view key, std::string_view value) {
    HATTR_THROW_UNLESS(isValidKey(key), "metadata key {}: expected letters, digits, '_', '.', '-'",
                       quotedField(key));
    HATTR_THROW_UNLESS(!hasControlCharacter(value), "metadata {}: a value cannot contain a line break "
                       "or another control character", key);
    fmt::format_to(std::back_inserter(buf), "# {}: {}\n", key, value);
  };
  put("format", kProfileFormat);
  put("units", "SI; each column name ends with its unit");
  put("frame", "W: paper plane z = 0, x right, y away from the writer, z up; f = force on the paper");
  put("subject", meta.subject);
  put("skill", meta.skill);
  put("device", meta.device);
  put("source", meta.source);
  put("created_utc", meta.created_utc);
  put("rate_hz", fmt::format("{}", meta.nominal_rate_hz));
  for (const auto& [key, value] : meta.extra) {
    HATTR_THROW_UNLESS(!isFormatKey(key) && key != "subject" && key != "skill" && key != "device" && key != "source" &&
                           key != "created_utc" && key != "rate_hz",
                       "metadata key {} is reserved", quotedField(key));
    put(key, value);
  }

  // Column row: every stored channel, raw ones only when present.
  std::vector<Channel> channels;
  for (const auto& info : allChannels()) {
    if (!info.derived && !needsRawChannel(info.channel, raw)) channels.push_back(info.channel);
  }
  for (std::size_t i = 0; i < channels.size(); ++i) {
    fmt::format_to(std::back_inserter(buf), "{}{}_{}", i ? "," : "", channelInfo(channels[i]).name,
                   channelInfo(channels[i]).unit);
  }
  buf.push_back('\n');

  // Data: shortest representation that reads back bit for bit.
  for (const Sample& s : profile.samples()) {
    for (std::size_t i = 0; i < channels.size(); ++i) {
      if (i) buf.push_back(',');
      fmt::format_to(std::back_inserter(buf), "{}", channelValue(s, channels[i]));
    }
    buf.push_back('\n');
  }
  out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
}

void writeProfileCsv(const HapticProfile& profile, const std::filesystem::path& file, Overwrite overwrite) {
  std::ostringstream text;
  writeProfileCsv(profile, text);
  writeFileAtomically(file, text.view(), overwrite);
}

}  // namespace hattr::io
