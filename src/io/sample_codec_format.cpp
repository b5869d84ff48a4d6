// The compact sample encoding's shared parts (sample_codec_internal.hpp): channels' roles and
// predictors, the header's checks and the decoded columns, as both revisions have them.
// Compiled with -ffp-contract=off (src/CMakeLists.txt), as every file of the encoding that
// computes with doubles.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "hattr/core/channel.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/sample.hpp"
#include "sample_codec_internal.hpp"

namespace hattr::io::detail {

// ---- Channels' roles and predictors -----------------------------------------------------

/// The user's and the guidance force channel of a commanded-force channel's axis.
std::pair<Channel, Channel> commandParts(Channel cmd) {
  switch (cmd) {
    case Channel::kCmdFx: return {Channel::kFx, Channel::kGuideFx};
    case Channel::kCmdFy: return {Channel::kFy, Channel::kGuideFy};
    default: return {Channel::kFz, Channel::kGuideFz};
  }
}

// What kind of channel a channel is.
bool isCommand(Channel c) { return c == Channel::kCmdFx || c == Channel::kCmdFy || c == Channel::kCmdFz; }
bool isPosition(Channel c) { return c == Channel::kX || c == Channel::kY || c == Channel::kZ; }
bool isVelocity(Channel c) { return c == Channel::kVx || c == Channel::kVy || c == Channel::kVz; }
bool isUserForce(Channel c) { return c == Channel::kFx || c == Channel::kFy || c == Channel::kFz; }

/// The velocity channel of a position channel's axis.
Channel velocityOf(Channel position) {
  return position == Channel::kX ? Channel::kVx : position == Channel::kY ? Channel::kVy : Channel::kVz;
}

/// True if `channels` holds `c`.
bool stores(std::span<const Channel> channels, Channel c) {
  return std::find(channels.begin(), channels.end(), c) != channels.end();
}

/// The column of `c` in `channels`.
std::size_t columnOf(std::span<const Channel> channels, Channel c) {
  return static_cast<std::size_t>(std::find(channels.begin(), channels.end(), c) - channels.begin());
}

/// The predictor of each channel: `chosen` is what a continuous channel gets (kQuadratic in
/// hsc1, kChosen in hsc2); the commanded force needs its axis's other two channels.
Predictor fixedOrChosen(Channel c, std::span<const Channel> channels, Predictor chosen) {
  if (isCommand(c)) {
    const auto [user, guide] = commandParts(c);
    return stores(channels, user) && stores(channels, guide) ? Predictor::kCommand : chosen;
  }
  switch (c) {
    case Channel::kContact:
    case Channel::kPenDown:
    case Channel::kPressure: return Predictor::kPrevious;
    case Channel::kTime:
    case Channel::kAzimuth:
    case Channel::kAltitude: return Predictor::kLine;
    default: return chosen;
  }
}

/// How many options a channel under `p` chooses from per block (0: it does not choose).
std::size_t optionCount(Predictor p) {
  return p == Predictor::kChosenKinematic ? kKinematicOptions : p == Predictor::kChosen ? kOptions : 0;
}

/// In whole steps the commanded force is predicted from its parts only where all three share
/// the step (else their difference is not in its steps): a quadratic otherwise.
Predictor stepPredictor(Predictor p, std::span<const Channel> channels, std::span<const double> steps, std::size_t c) {
  if (p != Predictor::kCommand) return p;
  const auto [user, guide] = commandParts(channels[c]);
  const bool same = steps[c] == steps[columnOf(channels, user)] && steps[c] == steps[columnOf(channels, guide)];
  return same ? Predictor::kCommand : Predictor::kQuadratic;
}

/// The columns in the order they can be decoded: positions predicted from their velocities
/// after those, every commanded force after its parts.
std::vector<std::size_t> decodingOrder(std::span<const Predictor> predictors) {
  const auto group = [](Predictor p) { return p == Predictor::kChosenKinematic ? 1 : p == Predictor::kCommand ? 2 : 0; };
  std::vector<std::size_t> order;
  for (int g = 0; g < 3; ++g) {
    for (std::size_t c = 0; c < predictors.size(); ++c) {
      if (group(predictors[c]) == g) order.push_back(c);
    }
  }
  return order;
}

// ---- The header's fields and the decoded columns ---------------------------------------

/// A channel's name, for messages.
std::string_view nameOf(Channel c) { return channelInfo(c).name; }

/// The header's first 12 bytes, checked against what the store says the blob holds.
BlockHeader readBlockHeader(std::string_view blob, std::span<const Channel> channels, std::size_t count,
                            std::size_t channel_bytes) {
  const std::size_t n = get<std::uint32_t>(blob, 4);
  const std::size_t m = get<std::uint16_t>(blob, 8);
  const auto flags = get<std::uint8_t>(blob, 10);
  HATTR_THROW_UNLESS((flags & ~kQuantized) == 0 && get<std::uint8_t>(blob, 11) == 0,
                     "samples: the encoded block's flags are {:#04x} {:#04x}, expected 0x00 or 0x01, then 0x00", flags,
                     get<std::uint8_t>(blob, 11));
  HATTR_THROW_UNLESS(n == count, "samples: the encoded block holds {} samples, expected {}", n, count);
  HATTR_THROW_UNLESS(m == channels.size(), "samples: the encoded block holds {} channels, expected {}", m,
                     channels.size());
  HATTR_THROW_UNLESS(blob.size() >= kHeaderBytes + m * channel_bytes + 8,
                     "samples: the encoded block is cut short in its header ({} bytes)", blob.size());
  return {n, m, (flags & kQuantized) != 0};
}

/// One channel's entry of the header: its number and predictor checked, its step returned
/// (finite and > 0 in a quantized block, 0 in a lossless one).
double readChannelEntry(std::string_view blob, std::size_t at, std::size_t c, Channel channel, Predictor expected,
                        bool quantized, std::size_t step_at) {
  const auto number = get<std::uint8_t>(blob, at);
  const auto predictor = get<std::uint8_t>(blob, at + 1);
  HATTR_THROW_UNLESS(number == static_cast<std::uint8_t>(channel), "samples: encoded channel {} is number {}, expected {} ({})",
                     c, number, static_cast<int>(channel), nameOf(channel));
  HATTR_THROW_UNLESS(predictor == static_cast<std::uint8_t>(expected), "samples: channel {}: predictor {}, expected {}",
                     nameOf(channel), predictor, static_cast<int>(expected));
  const double step = get<double>(blob, at + step_at);
  HATTR_THROW_UNLESS(quantized ? std::isfinite(step) && step > 0.0 : step == 0.0, "samples: channel {}: step {} in a {} block",
                     nameOf(channel), step, quantized ? "quantized" : "lossless");
  return step;
}

/// Turns decoded whole steps into values.
void fromSteps(const std::uint64_t* k, double step, double* values, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) values[i] = static_cast<double>(static_cast<std::int64_t>(k[i])) * step;
}

/// The decoded columns as samples; every value must be finite, as a profile's are.
std::vector<Sample> toSamples(const double* values, std::span<const Channel> channels, std::size_t n) {
  std::vector<Sample> samples(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t c = 0; c < channels.size(); ++c) {
      const double v = values[c * n + i];
      HATTR_THROW_UNLESS(std::isfinite(v), "samples: channel {}, sample {}: decoded a non-finite value", nameOf(channels[c]), i);
      setChannelValue(samples[i], channels[c], v);
    }
  }
  return samples;
}

}  // namespace hattr::io::detail
