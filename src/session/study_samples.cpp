// How a trial's samples are packed into the samples tables' blocks, on either store: the
// compact encoding (io/sample_codec) this build writes, and schema 3's rows of doubles, still
// read. Times in seconds; the other channels in the units of core/channel.hpp.

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/session/study_database.hpp"
#include "study_database_internal.hpp"

namespace hattr::session {

using detail::decodeRowSamples;
using detail::storedChannels;

/// The channels a block stores: every channel not derived and not needing a raw channel the
/// profile lacks.
std::vector<Channel> detail::storedChannels(const RawChannels& raw) {
  std::vector<Channel> channels;
  for (const auto& info : allChannels()) {
    if (!info.derived && !needsRawChannel(info.channel, raw)) channels.push_back(info.channel);
  }
  return channels;
}

namespace {

/// Whether the profile's times stay strictly increasing in whole steps of `step`.
bool timesStayIncreasing(const HapticProfile& profile, double step) {
  long long last = std::numeric_limits<long long>::min();
  for (const Sample& s : profile.samples()) {
    const long long k = std::llround(s.t_s / step);
    if (k <= last) return false;
    last = k;
  }
  return true;
}

}  // namespace

std::string encodeTrialSamples(const HapticProfile& profile, const io::ChannelResolution& resolution) {
  const auto channels = storedChannels(profile.rawChannels());
  // At the declared resolution, unless a value lies beyond its range or two samples' times
  // would fall on one step: then losslessly (the block says which), so nothing is lost and
  // every stored profile reads back.
  if (!resolution.empty() && timesStayIncreasing(profile, resolution.at(Channel::kTime))) {
    try {
      return io::encodeSamples(profile.samples(), channels, resolution);
    } catch (const InputError&) {
    }
  }
  return io::encodeSamples(profile.samples(), channels);
}

/// Schema 3's rows of little-endian doubles, one row per sample.
std::vector<Sample> detail::decodeRowSamples(std::string_view bytes, const RawChannels& raw, std::size_t count) {
  static_assert(std::endian::native == std::endian::little, "the samples table stores little-endian doubles");
  const auto channels = storedChannels(raw);
  HATTR_THROW_UNLESS(count <= bytes.size() && bytes.size() == count * channels.size() * sizeof(double),
                     "samples: {} bytes stored, expected {} samples × {} channels × 8", bytes.size(), count,
                     channels.size());
  std::vector<Sample> samples(count);
  const char* in = bytes.data();
  for (Sample& s : samples) {
    for (const Channel c : channels) {
      double v = 0.0;
      std::memcpy(&v, in, sizeof v);
      in += sizeof v;
      setChannelValue(s, c, v);
    }
  }
  return samples;
}

std::vector<Sample> decodeTrialSamples(std::string_view bytes, std::string_view encoding, const RawChannels& raw,
                                       std::size_t count) {
  if (encoding == kCompactSamples || encoding == kCompactSamplesV1) {
    // The block says its revision too: the two must agree.
    const std::string_view starts_as = io::sampleEncodingOf(bytes);
    HATTR_THROW_UNLESS(starts_as == encoding, "samples: a block marked {} starts as {} (damaged)", encoding,
                       starts_as.empty() ? "neither hsc1 nor hsc2" : starts_as);
    return io::decodeSamples(bytes, storedChannels(raw), count);
  }
  if (encoding == kRowSamples) return decodeRowSamples(bytes, raw, count);
  throw InputError(fmt::format("samples: encoding \"{}\": expected {}, {} or {}", encoding, kCompactSamples,
                               kCompactSamplesV1, kRowSamples));
}

}  // namespace hattr::session
