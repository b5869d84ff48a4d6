#pragma once
// The compact sample encoding's shared parts (include/hattr/io/sample_codec.hpp): the block
// header's constants and fields, how each channel is predicted and laid out, and the checks and
// conversions both revisions share (sample_codec_format.cpp). Values are in each channel's SI
// unit; steps too.
//
// Two revisions are read: hsc1 (a fixed predictor per channel, byte planes; what schema 4
// first wrote) and hsc2 (what this build writes: a predictor chosen per block of samples, and
// the measured channels coded as bit lengths and bits). docs/study-store.md has both layouts.
//
// The other parts: sample_codec_predictors_internal.hpp (the predictions),
// sample_bits_internal.hpp (byte planes, bit lengths and bits), sample_codec_framing_internal.hpp
// (zstd), sample_codec_v1.cpp and sample_codec_v2.cpp (each revision).

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hattr/core/channel.hpp"
#include "hattr/core/sample.hpp"
#include "hattr/io/sample_codec.hpp"

namespace hattr::io::detail {

static_assert(std::endian::native == std::endian::little, "the sample encoding is little-endian");

inline constexpr char kMagicV1[4] = {'H', 'S', 'C', '\x01'};  // hattr sample columns, revision 1
inline constexpr char kMagicV2[4] = {'H', 'S', 'C', '\x02'};  // revision 2
inline constexpr std::size_t kHeaderBytes = 12;               // magic, u32 count, u16 channels, u8 flags, u8 0
inline constexpr std::size_t kChannelBytesV1 = 10;            // u8 channel, u8 predictor, f64 step
inline constexpr std::size_t kChannelBytesV2 = 11;            // u8 channel, u8 predictor, u8 coding, f64 step
inline constexpr std::size_t kBlock = 128;                    // samples per predictor choice (hsc2)
inline constexpr std::uint8_t kQuantized = 1;

/// How a channel's value is predicted from what was decoded before it.
enum class Predictor : std::uint8_t {
  kPrevious = 0,          ///< the last value (flags, raw pressure)
  kLine = 1,              ///< through the last two (time, tilt)
  kQuadratic = 2,         ///< through the last three (hsc1's continuous channels)
  kCommand = 3,           ///< the commanded force: guidance force minus the user's force, same axis
  kChosen = 4,            ///< hsc2: one of the options below, chosen per block of samples
  kChosenKinematic = 5,   ///< hsc2: the same, or from the axis's velocity (positions)
};

/// The predictions a kChosen channel's blocks choose from; kChosenKinematic adds the last two.
enum class Option : std::uint8_t {
  kPrevious = 0,            ///< the last value
  kLine = 1,                ///< through the last two
  kQuadratic = 2,           ///< through the last three
  kCubic = 3,               ///< through the last four
  kPeriodic4 = 4,           ///< the quadratic, plus what it missed 4 samples before
  kPeriodic8 = 5,           ///< the quadratic, plus what it missed 8 samples before
  kKinematic = 6,           ///< the last position moved by the interval times a·v_i + b·v_(i-1)
  kKinematicPeriodic4 = 7,  ///< that, plus what it missed 4 samples before
};
inline constexpr std::size_t kOptions = 6;           // kPrevious .. kPeriodic8
inline constexpr std::size_t kKinematicOptions = 8;  // and the two kinematic ones
static_assert(kOptions == static_cast<std::size_t>(Option::kKinematic) &&
              kKinematicOptions == static_cast<std::size_t>(Option::kKinematicPeriodic4) + 1);

/// How a channel's residuals are laid out before zstd (hsc2).
enum class Coding : std::uint8_t {
  kBytePlanes = 0,  ///< all first bytes, then all second bytes, ... (with the other such channels)
  kBitLengths = 1,  ///< each residual's bit length (as a change from the last), then its bits below the top one
};

// ---- Channels' roles and predictors (sample_codec_format.cpp) ----------------------------

/// The user's and the guidance force channel of a commanded-force channel's axis.
std::pair<Channel, Channel> commandParts(Channel cmd);

/// What kind of channel `c` is: a commanded force, a position, a velocity, the user's force.
bool isCommand(Channel c);
bool isPosition(Channel c);
bool isVelocity(Channel c);
bool isUserForce(Channel c);

/// The velocity channel of a position channel's axis.
Channel velocityOf(Channel position);

/// True if `channels` holds `c`.
bool stores(std::span<const Channel> channels, Channel c);

/// The column of `c` in `channels` (channels.size() if it is not there).
std::size_t columnOf(std::span<const Channel> channels, Channel c);

/// The predictor of each channel: `chosen` is what a continuous channel gets (kQuadratic in
/// hsc1, kChosen in hsc2); the commanded force needs its axis's other two channels.
Predictor fixedOrChosen(Channel c, std::span<const Channel> channels, Predictor chosen);

/// How many options a channel under `p` chooses from per block (0: it does not choose).
std::size_t optionCount(Predictor p);

/// In whole steps the commanded force is predicted from its parts only where all three share
/// the step (else their difference is not in its steps): a quadratic otherwise.
Predictor stepPredictor(Predictor p, std::span<const Channel> channels, std::span<const double> steps, std::size_t c);

/// The columns in the order they can be decoded: positions predicted from their velocities
/// after those, every commanded force after its parts.
std::vector<std::size_t> decodingOrder(std::span<const Predictor> predictors);

// ---- The header's fields and the decoded columns (sample_codec_format.cpp) ---------------

/// Appends `value`'s bytes (little-endian) to `out`.
template <class T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

/// The value whose bytes start at `at` in `blob` (the caller checked that they are there).
template <class T>
T get(std::string_view blob, std::size_t at) {
  T value;
  std::memcpy(&value, blob.data() + at, sizeof(T));
  return value;
}

/// A channel's name, for messages.
std::string_view nameOf(Channel c);

/// The header's first 12 bytes, checked against what the store says the blob holds.
struct BlockHeader {
  std::size_t n = 0;
  std::size_t m = 0;
  bool quantized = false;
};

/// Reads and checks the header's first 12 bytes; `channel_bytes` is the revision's per channel.
BlockHeader readBlockHeader(std::string_view blob, std::span<const Channel> channels, std::size_t count,
                            std::size_t channel_bytes);

/// One channel's entry of the header: its number and predictor checked, its step returned
/// (finite and > 0 in a quantized block, 0 in a lossless one).
double readChannelEntry(std::string_view blob, std::size_t at, std::size_t c, Channel channel, Predictor expected,
                        bool quantized, std::size_t step_at);

/// Turns decoded whole steps into values.
void fromSteps(const std::uint64_t* k, double step, double* values, std::size_t n);

/// The decoded columns as samples; every value must be finite, as a profile's are.
std::vector<Sample> toSamples(const double* values, std::span<const Channel> channels, std::size_t n);

// ---- The revisions (sample_codec_v1.cpp, sample_codec_v2.cpp) ---------------------------

/// An hsc1 block: a fixed predictor per channel, every residual in byte planes.
std::vector<Sample> decodeRevision1(std::string_view blob, std::span<const Channel> channels, std::size_t count);

/// An hsc2 block.
std::vector<Sample> decodeRevision2(std::string_view blob, std::span<const Channel> channels, std::size_t count);

/// `samples` as an hsc2 block (encodeSamples checked their count, the channels' and the level).
std::string encodeRevision2(std::span<const Sample> samples, std::span<const Channel> channels,
                            const ChannelResolution& resolution, int level);

}  // namespace hattr::io::detail
