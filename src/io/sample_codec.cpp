// The compact sample encoding (include/hattr/io/sample_codec.hpp): its public calls. Compiled
// with -ffp-contract=off (src/CMakeLists.txt), as every file of the encoding that computes with
// doubles: the predictions must round the same in every build.
//
// Two revisions are read: hsc1 (a fixed predictor per channel, byte planes; what schema 4
// first wrote) and hsc2 (what this build writes: a predictor chosen per block of samples, and
// the measured channels coded as bit lengths and bits). docs/study-store.md has both layouts.
// The parts, one job each: sample_codec_format.cpp (the header and channels' roles),
// sample_codec_predictors.cpp (the predictions), sample_bits.cpp (byte planes, bit lengths and
// bits), sample_codec_framing.cpp (zstd), sample_codec_v1.cpp and sample_codec_v2.cpp (each
// revision).

#include "hattr/io/sample_codec.hpp"

#include <cmath>
#include <cstddef>
#include <cstring>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/channel.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/sample.hpp"
#include "sample_codec_internal.hpp"

namespace hattr::io {

const ChannelResolution& defaultResolution() {
  static const ChannelResolution resolution = [] {
    ChannelResolution r;
    r[Channel::kTime] = 1e-6;
    for (Channel c : {Channel::kX, Channel::kY, Channel::kZ}) r[c] = 1e-6;
    for (Channel c : {Channel::kVx, Channel::kVy, Channel::kVz}) r[c] = 1e-5;
    for (Channel c : {Channel::kFx, Channel::kFy, Channel::kFz, Channel::kCmdFx, Channel::kCmdFy, Channel::kCmdFz,
                      Channel::kGuideFx, Channel::kGuideFy, Channel::kGuideFz}) {
      r[c] = 1e-3;
    }
    for (Channel c : {Channel::kContact, Channel::kPenDown, Channel::kPressure}) r[c] = 1.0;
    for (Channel c : {Channel::kAzimuth, Channel::kAltitude}) r[c] = 1e-4;
    return r;
  }();
  return resolution;
}

ChannelResolution parseResolution(std::string_view json_text, std::string_view where) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: expected \"lossless\", \"default\" or an object of channel steps, got {} ({})",
                                 where, json_text, e.what()));
  }
  if (json.is_string() && json.get<std::string>() == "lossless") return {};
  if (json.is_string() && json.get<std::string>() == "default") return defaultResolution();
  HATTR_THROW_UNLESS(json.is_object(), "{}: expected \"lossless\", \"default\" or an object of channel steps, got {}",
                     where, json.dump());
  // Named channels take their step; the others keep the default's.
  ChannelResolution resolution = defaultResolution();
  for (const auto& [name, step] : json.items()) {
    const auto channel = channelFromName(name);
    HATTR_THROW_UNLESS(channel && !channelInfo(*channel).derived,
                       "{}: \"{}\": expected a stored channel (t, x, y, z, vx, vy, vz, fx, fy, fz, cmd_fx, cmd_fy, "
                       "cmd_fz, guide_fx, guide_fy, guide_fz, contact, pen_down, pressure, azimuth, altitude)",
                       where, name);
    HATTR_THROW_UNLESS(step.is_number() && std::isfinite(step.get<double>()) && step.get<double>() > 0.0,
                       "{}: \"{}\": expected a step > 0 in {}, got {}", where, name, channelInfo(*channel).unit,
                       step.dump());
    resolution[*channel] = step.get<double>();
  }
  return resolution;
}

std::string resolutionJson(const ChannelResolution& resolution) {
  if (resolution.empty()) return "\"lossless\"";
  nlohmann::json json = nlohmann::json::object();
  for (const auto& [channel, step] : resolution) json[std::string(detail::nameOf(channel))] = step;
  return json.dump();
}

bool isEncodedSamples(std::string_view blob) noexcept { return !sampleEncodingOf(blob).empty(); }

std::string_view sampleEncodingOf(std::string_view blob) noexcept {
  if (blob.size() < sizeof detail::kMagicV1) return {};
  if (std::memcmp(blob.data(), detail::kMagicV1, sizeof detail::kMagicV1) == 0) return kSampleEncodingV1;
  if (std::memcmp(blob.data(), detail::kMagicV2, sizeof detail::kMagicV2) == 0) return kSampleEncoding;
  return {};
}

std::string encodeSamples(std::span<const Sample> samples, std::span<const Channel> channels,
                          const ChannelResolution& resolution, int level) {
  const std::size_t n = samples.size();
  const std::size_t m = channels.size();
  HATTR_THROW_UNLESS(n <= 0xFFFFFFFFu && m >= 1 && m <= 0xFFFF, "sample encoding: {} samples on {} channels", n, m);
  HATTR_THROW_UNLESS(level >= 1 && level <= 19, "sample encoding: zstd level: expected 1 to 19, got {}", level);
  return detail::encodeRevision2(samples, channels, resolution, level);
}

std::vector<Sample> decodeSamples(std::string_view blob, std::span<const Channel> channels, std::size_t count) {
  const std::string_view revision = sampleEncodingOf(blob);
  HATTR_THROW_UNLESS(!revision.empty() && blob.size() >= detail::kHeaderBytes,
                     "samples: expected an encoded block (starting \"HSC\\x01\" or \"HSC\\x02\", at least {} bytes), got {} bytes",
                     detail::kHeaderBytes, blob.size());
  return revision == kSampleEncoding ? detail::decodeRevision2(blob, channels, count)
                                     : detail::decodeRevision1(blob, channels, count);
}

}  // namespace hattr::io
