#pragma once
/// The compact encoding of a trial's samples (issue 17): what the study store keeps.
///
/// Lossless by default: each stored channel, column by column, is predicted from what came
/// before it, and only the difference of the bit patterns is kept, zigzagged, laid out and
/// compressed with zstd. Continuous channels choose, per block of 128 samples, the prediction
/// that leaves the fewest bits (polynomials through the last values, the same with what they
/// missed 4 or 8 samples before, and for positions the velocity's step); time and tilt follow a
/// line, flags and raw pressure their last value, and the commanded force is predicted as
/// guidance force minus the user's force. Positions, velocities and the user's force are kept
/// as each residual's bit length and its bits, the others in byte planes. Decoding gives back
/// every double bit for bit. The predictions are IEEE double operations compiled without
/// contraction, so any conforming build decodes any blob.
///
/// Optionally a declared per-channel resolution (e.g. 1 µm, 1 mN): each value is stored as the
/// nearest whole multiple k·step, the integers predicted as in the first revision (a quadratic
/// for the continuous channels) and kept in byte planes, and the reader returns exactly k·step.
/// docs/study-store.md has the format and the measurements that chose it
/// (bench/sample_compression.py, bench/sample_codec_parts.py). Blocks of the first revision
/// (hsc1: one fixed prediction per channel, byte planes only) are still read.
#include <cstddef>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/channel.hpp"
#include "hattr/core/sample.hpp"

namespace hattr::io {

/// Each stored channel's step [its SI unit]; empty: lossless.
using ChannelResolution = std::map<Channel, double>;

/// hattr's default declared resolution, below any pen's sensor resolution: 1 µs, 1 µm,
/// 10 µm/s, 1 mN (every force), 1e-4 rad, and whole units for flags and raw pressure.
const ChannelResolution& defaultResolution();

/// Reads a resolution from its JSON form: "lossless", "default", or an object of channel name
/// -> step (steps finite and > 0; the channels not named keep the default's step). Throws
/// InputError naming `where`, the channel and what was expected.
ChannelResolution parseResolution(std::string_view json_text, std::string_view where);
/// Its JSON form, as parseResolution reads it ("lossless" when empty).
std::string resolutionJson(const ChannelResolution& resolution);

/// Encodes `samples` on `channels` (the stored channels, in order). With a resolution, it must
/// give a step for every channel, and every value must be within 2^51 steps of zero. `level`
/// is zstd's (1–19). Throws InputError for what cannot be encoded.
std::string encodeSamples(std::span<const Sample> samples, std::span<const Channel> channels,
                          const ChannelResolution& resolution = {}, int level = 1);

/// Decodes a blob of encodeSamples on the same channels; `count` is the number of samples
/// the store says it holds. Throws InputError (what is wrong, expected, got) for a blob that is
/// not one, is cut short, names other channels or another count.
std::vector<Sample> decodeSamples(std::string_view blob, std::span<const Channel> channels, std::size_t count);

/// The encoding encodeSamples writes, as the study store names it, and the first revision's.
inline constexpr std::string_view kSampleEncoding = "hsc2";
inline constexpr std::string_view kSampleEncodingV1 = "hsc1";

/// "hsc1" or "hsc2" for a blob that starts as either revision does (both are read), else "".
std::string_view sampleEncodingOf(std::string_view blob) noexcept;

/// True if `blob` starts as a block of either revision does (to tell them from older stores' raw rows).
bool isEncodedSamples(std::string_view blob) noexcept;

}  // namespace hattr::io
