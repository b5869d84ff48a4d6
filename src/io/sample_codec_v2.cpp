// The compact sample encoding's second revision, hsc2 (docs/study-store.md): what this build
// writes. A predictor chosen per block of samples, and the measured channels coded as bit
// lengths and bits. Compiled with -ffp-contract=off (src/CMakeLists.txt), as every file of the
// encoding that computes with doubles.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hattr/core/channel.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/sample.hpp"
#include "hattr/io/sample_codec.hpp"
#include "sample_bits_internal.hpp"
#include "sample_codec_framing_internal.hpp"
#include "sample_codec_internal.hpp"
#include "sample_codec_predictors_internal.hpp"

namespace hattr::io::detail {
namespace {

constexpr double kLargestSteps = 2251799813685248.0;  // 2^51: below it llround(k·step / step) is k again

/// hsc2: lossless continuous channels choose per block, and a position whose velocity and time
/// are stored may be predicted from them. Whole steps keep hsc1's quadratic: choosing gains them
/// under 1 % (docs/study-store.md) and would cost a third more time to encode.
Predictor predictorV2(Channel c, std::span<const Channel> channels, bool quantized) {
  if (quantized) return fixedOrChosen(c, channels, Predictor::kQuadratic);
  const bool kinematic = isPosition(c) && stores(channels, velocityOf(c)) && stores(channels, Channel::kTime);
  return fixedOrChosen(c, channels, kinematic ? Predictor::kChosenKinematic : Predictor::kChosen);
}

/// hsc2: the measured channels (positions, velocities, the user's force) keep noise in their
/// last digits, and are coded as bit lengths and bits when lossless; the others as byte planes.
Coding codingV2(Channel c, bool quantized) {
  return !quantized && (isPosition(c) || isVelocity(c) || isUserForce(c)) ? Coding::kBitLengths : Coding::kBytePlanes;
}

/// What an hsc2 header says about each channel, beyond the first 12 bytes.
struct LayoutV2 {
  std::vector<Predictor> predictors;  ///< as stored (kCommand even where steps make it a quadratic)
  std::vector<Predictor> effective;   ///< what predicts each column
  std::vector<Coding> codings;
  std::vector<double> steps;
  std::vector<std::pair<double, double>> kinematics;  ///< a and b, per channel (kChosenKinematic only)
  std::size_t header_bytes = 0;                        ///< up to the content size
  std::size_t chosen = 0, in_planes = 0, in_bits = 0;  ///< channels of each kind
  std::vector<std::size_t> slot;  ///< each channel's column of residuals: byte-plane channels first, in order
};

/// The parts of an hsc2 frame's content, after the header's copy, in order.
struct ContentV2 {
  std::size_t choices = 0;      ///< bytes: one per block of each chosen channel
  std::size_t planes = 0;       ///< bytes: 8 per sample of each byte-plane channel
  std::size_t lengths = 0;      ///< bytes: one per sample of each bit-length channel
  std::size_t fixed(std::size_t header_bytes) const { return header_bytes + choices + planes + lengths; }
};

/// The sizes of the content's parts before the bits, for `n` samples.
ContentV2 contentOf(const LayoutV2& layout, std::size_t n) {
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  return {blocks * layout.chosen, n * layout.in_planes * 8, n * layout.in_bits};
}

/// How many channels choose per block and how many take each layout, and each one's slot.
void countKinds(LayoutV2& layout) {
  for (std::size_t c = 0; c < layout.effective.size(); ++c) {
    if (optionCount(layout.effective[c]) > 0) ++layout.chosen;
    if (layout.codings[c] == Coding::kBitLengths) {
      ++layout.in_bits;
    } else {
      ++layout.in_planes;
    }
  }
  layout.slot.resize(layout.effective.size());
  for (std::size_t c = 0, planes = 0, bits = layout.in_planes; c < layout.slot.size(); ++c) {
    layout.slot[c] = layout.codings[c] == Coding::kBitLengths ? bits++ : planes++;
  }
}

/// The rest of an hsc2 header, each field checked against what this build writes for these
/// channels.
LayoutV2 readLayoutV2(std::string_view blob, std::span<const Channel> channels, const BlockHeader& header) {
  LayoutV2 layout;
  const std::size_t m = header.m;
  layout.predictors.resize(m);
  layout.codings.resize(m);
  layout.steps.resize(m);
  layout.kinematics.resize(m);
  std::size_t kinematic = 0;
  for (std::size_t c = 0; c < m; ++c) {
    const std::size_t at = kHeaderBytes + c * kChannelBytesV2;
    layout.predictors[c] = predictorV2(channels[c], channels, header.quantized);
    layout.steps[c] = readChannelEntry(blob, at, c, channels[c], layout.predictors[c], header.quantized, 3);
    layout.codings[c] = codingV2(channels[c], header.quantized);
    const auto coding = get<std::uint8_t>(blob, at + 2);
    HATTR_THROW_UNLESS(coding == static_cast<std::uint8_t>(layout.codings[c]), "samples: channel {}: layout {}, expected {}",
                       nameOf(channels[c]), coding, static_cast<int>(layout.codings[c]));
    if (layout.predictors[c] == Predictor::kChosenKinematic) ++kinematic;
  }
  // The kinematic predictions' a and b, after the channels.
  std::size_t at = kHeaderBytes + m * kChannelBytesV2;
  HATTR_THROW_UNLESS(blob.size() >= at + kinematic * 16 + 8, "samples: the encoded block is cut short in its header ({} bytes)",
                     blob.size());
  for (std::size_t c = 0; c < m; ++c) {
    if (layout.predictors[c] != Predictor::kChosenKinematic) continue;
    layout.kinematics[c] = {get<double>(blob, at), get<double>(blob, at + 8)};
    HATTR_THROW_UNLESS(std::isfinite(layout.kinematics[c].first) && std::isfinite(layout.kinematics[c].second),
                       "samples: channel {}: kinematic coefficients {} and {}, expected finite numbers", nameOf(channels[c]),
                       layout.kinematics[c].first, layout.kinematics[c].second);
    at += 16;
  }
  layout.header_bytes = at;
  for (std::size_t c = 0; c < m; ++c) {
    layout.effective.push_back(
        header.quantized ? stepPredictor(layout.predictors[c], channels, layout.steps, c) : layout.predictors[c]);
  }
  countKinds(layout);
  return layout;
}

/// A column's kinematic prediction reads the time and the axis's velocity, decoded before it.
Kinematics kinematicsOf(const LayoutV2& layout, std::span<const Channel> channels, std::size_t c, const double* values,
                        std::size_t n) {
  if (layout.effective[c] != Predictor::kChosenKinematic) return {};
  return {values + columnOf(channels, Channel::kTime) * n, values + columnOf(channels, velocityOf(channels[c])) * n,
          layout.kinematics[c].first, layout.kinematics[c].second};
}

// ---- Decoding: the parts of decodeRevision2 ----------------------------------------------

/// Each chosen channel's choices, one per block (null for the other channels), read from
/// `bytes + at` and each checked against the channel's options; `at` moves past them.
std::vector<const std::uint8_t*> readChoices(const unsigned char* bytes, std::size_t& at, const LayoutV2& layout,
                                             std::span<const Channel> channels, std::size_t n) {
  const std::size_t m = channels.size();
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<const std::uint8_t*> choices(m, nullptr);
  for (std::size_t c = 0; c < m; ++c) {
    const std::size_t options = optionCount(layout.effective[c]);
    if (options == 0) continue;
    choices[c] = bytes + at;
    for (std::size_t b = 0; b < blocks; ++b) {
      HATTR_THROW_UNLESS(choices[c][b] < options, "samples: channel {}, block {}: prediction {}, expected below {} (damaged)",
                         nameOf(channels[c]), b, choices[c][b], options);
    }
    at += blocks;
  }
  return choices;
}

// ---- Encoding: the parts of encodeRevision2 ----------------------------------------------

/// The header's channel entries, appended after its first 12 bytes: how each channel is
/// predicted and laid out, and its step (the declared resolution's; 0 when lossless).
LayoutV2 appendChannelEntries(std::string& blob, std::span<const Channel> channels, const ChannelResolution& resolution,
                              bool quantized) {
  const std::size_t m = channels.size();
  LayoutV2 layout;
  for (const Channel c : channels) {
    layout.predictors.push_back(predictorV2(c, channels, quantized));
    layout.codings.push_back(codingV2(c, quantized));
    double step = 0.0;
    if (quantized) {
      const auto it = resolution.find(c);
      HATTR_THROW_UNLESS(it != resolution.end() && std::isfinite(it->second) && it->second > 0.0,
                         "sample encoding: the declared resolution has no step > 0 for channel {}", nameOf(c));
      step = it->second;
    }
    layout.steps.push_back(step);
    put<std::uint8_t>(blob, static_cast<std::uint8_t>(c));
    put<std::uint8_t>(blob, static_cast<std::uint8_t>(layout.predictors.back()));
    put<std::uint8_t>(blob, static_cast<std::uint8_t>(layout.codings.back()));
    put<double>(blob, step);
  }
  for (std::size_t c = 0; c < m; ++c) {
    layout.effective.push_back(quantized ? stepPredictor(layout.predictors[c], channels, layout.steps, c)
                                         : layout.predictors[c]);
  }
  countKinds(layout);
  return layout;
}

/// Each column as doubles, column after column; each sample read once.
std::unique_ptr<double[]> columnsOf(std::span<const Sample> samples, std::span<const Channel> channels) {
  const std::size_t n = samples.size();
  const std::size_t m = channels.size();
  auto values = std::make_unique_for_overwrite<double[]>(n * m);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t c = 0; c < m; ++c) values[c * n + i] = channelValue(samples[i], channels[c]);
  }
  return values;
}

/// Each column in the nearest whole steps of its channel (empty when lossless); every value
/// must be finite and within 2^51 steps of zero.
std::unique_ptr<std::uint64_t[]> wholeStepsOf(const double* values, const LayoutV2& layout, std::span<const Channel> channels,
                                              std::size_t n, bool quantized) {
  const std::size_t m = channels.size();
  auto k = std::make_unique_for_overwrite<std::uint64_t[]>(quantized ? n * m : 0);
  for (std::size_t c = 0; quantized && c < m; ++c) {
    for (std::size_t i = 0; i < n; ++i) {
      const double v = values[c * n + i] / layout.steps[c];
      HATTR_THROW_UNLESS(std::isfinite(values[c * n + i]), "sample encoding: channel {}, sample {}: not a number: {}",
                         nameOf(channels[c]), i, values[c * n + i]);
      HATTR_THROW_UNLESS(std::abs(v) <= kLargestSteps, "sample encoding: channel {}, sample {}: {} {} is beyond 2^51 steps of {} {}",
                         nameOf(channels[c]), i, values[c * n + i], channelInfo(channels[c]).unit, layout.steps[c],
                         channelInfo(channels[c]).unit);
      k[c * n + i] = static_cast<std::uint64_t>(std::llround(v));
    }
  }
  return k;
}

/// The kinematic predictions' a and b, fitted to this trial, appended after the channels.
void appendKinematics(std::string& blob, LayoutV2& layout, std::span<const Channel> channels, const double* values,
                      std::size_t n) {
  const std::size_t m = channels.size();
  layout.kinematics.resize(m);
  for (std::size_t c = 0; c < m; ++c) {
    if (layout.predictors[c] != Predictor::kChosenKinematic) continue;
    layout.kinematics[c] = fitKinematics(values + c * n, values + columnOf(channels, velocityOf(channels[c])) * n,
                                         values + columnOf(channels, Channel::kTime) * n, n);
    put<double>(blob, layout.kinematics[c].first);
    put<double>(blob, layout.kinematics[c].second);
  }
}

/// Each column's residuals against its predictions, zigzagged, in its slot of the words
/// returned; the chosen columns' choices appended to `content`, one byte per block.
std::unique_ptr<std::uint64_t[]> appendChoicesAndResiduals(std::string& content, const LayoutV2& layout,
                                                           std::span<const Channel> channels, const double* values,
                                                           const std::uint64_t* k, std::size_t n, bool quantized) {
  const std::size_t m = channels.size();
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  auto words = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
  for (std::size_t c = 0; c < m; ++c) {
    const Predictor p = layout.effective[c];
    const auto [user, guide] = commandParts(channels[c]);
    const bool command = p == Predictor::kCommand;
    std::uint8_t* choices = nullptr;
    if (optionCount(p) > 0) {
      content.resize(content.size() + blocks);
      choices = reinterpret_cast<std::uint8_t*>(content.data() + content.size() - blocks);
    }
    if (!quantized) {
      const double* column = values + c * n;
      if (choices != nullptr) {
        encodeChosenColumn(optionCount(p), column, kinematicsOf(layout, channels, c, values, n),
                           words.get() + layout.slot[c] * n, choices, n);
      } else {
        encodeColumn<Doubles>(p, column, command ? values + columnOf(channels, guide) * n : nullptr,
                              command ? values + columnOf(channels, user) * n : nullptr, words.get() + layout.slot[c] * n, n);
      }
    } else {
      encodeColumn<Steps>(p, k + c * n, command ? k + columnOf(channels, guide) * n : nullptr,
                          command ? k + columnOf(channels, user) * n : nullptr, words.get() + layout.slot[c] * n, n);
    }
  }
  return words;
}

/// The residuals appended to `content` in their layouts: the byte-plane channels' planes, the
/// bit-length channels' lengths, and their bits. Returns where each part of the content ends
/// (the choices, the planes, the lengths, the bits).
std::array<std::size_t, 4> appendResidualParts(std::string& content, const LayoutV2& layout, const std::uint64_t* words,
                                               std::size_t n) {
  const std::size_t planes_at = content.size();
  appendShuffled(content, words, n * layout.in_planes);
  const std::size_t lengths_at = content.size();
  for (std::size_t q = 0; q < layout.in_bits; ++q) appendLengthChanges(content, words + (layout.in_planes + q) * n, n);
  const std::size_t bits_at = content.size();
  content.reserve(bits_at + n * layout.in_bits * 8 + 8);
  BitWriter writer(content);
  for (std::size_t q = 0; q < layout.in_bits; ++q) appendBitsBelowTop(writer, words + (layout.in_planes + q) * n, n);
  writer.finish();
  return {planes_at, lengths_at, bits_at, content.size()};
}

}  // namespace

/// An hsc2 block.
std::vector<Sample> decodeRevision2(std::string_view blob, std::span<const Channel> channels, std::size_t count) {
  const BlockHeader header = readBlockHeader(blob, channels, count, kChannelBytesV2);
  const std::size_t n = header.n, m = header.m;
  const LayoutV2 layout = readLayoutV2(blob, channels, header);

  // The content's size, within what its parts allow, before anything is allocated.
  const ContentV2 parts = contentOf(layout, n);
  const std::size_t fixed = parts.fixed(layout.header_bytes);
  const std::size_t most = fixed + (n * layout.in_bits * 63 + 7) / 8;
  const auto content_size = get<std::uint64_t>(blob, layout.header_bytes);
  HATTR_THROW_UNLESS(content_size >= fixed && content_size <= most,
                     "samples: the encoded block says {} bytes of header and residuals, expected {} to {}", content_size,
                     fixed, most);
  const auto content = decompressContent(blob, layout.header_bytes, content_size);
  const auto* bytes = reinterpret_cast<const unsigned char*>(content.get());

  // Each chosen channel's choices, one per block.
  std::size_t at = layout.header_bytes;
  const std::vector<const std::uint8_t*> choices = readChoices(bytes, at, layout, channels, n);

  // The residuals: byte planes, then bit lengths and bits, each channel's in its slot.
  const auto words = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
  unshuffle(std::string_view(content.get() + at, parts.planes), words.get());
  at += parts.planes;
  std::vector<std::uint8_t> lengths(n * layout.in_bits);
  std::uint64_t total_bits = 0;
  for (std::size_t c = 0; c < m; ++c) {
    if (layout.codings[c] != Coding::kBitLengths) continue;
    const std::size_t q = layout.slot[c] - layout.in_planes;
    total_bits += readBitLengths(bytes + at + q * n, lengths.data() + q * n, n, nameOf(channels[c]));
  }
  at += parts.lengths;
  HATTR_THROW_UNLESS(content_size - at == (total_bits + 7) / 8,
                     "samples: the compressed residuals are damaged: {} bytes of bits, expected {}", content_size - at,
                     (total_bits + 7) / 8);
  BitReader bits(std::string_view(content.get() + at, content_size - at));
  for (std::size_t q = 0; q < layout.in_bits; ++q) {
    readBits(bits, lengths.data() + q * n, words.get() + (layout.in_planes + q) * n, n);
  }
  HATTR_THROW_UNLESS(bits.atCleanEnd(), "samples: the compressed residuals are damaged: their last byte has stray bits");

  // Each column from its residuals and predictions: positions after their velocities, the
  // commanded forces after their parts.
  const auto values = std::make_unique_for_overwrite<double[]>(n * m);
  const auto k = std::make_unique_for_overwrite<std::uint64_t[]>(header.quantized ? n * m : 0);
  for (const std::size_t c : decodingOrder(layout.effective)) {
    const Predictor p = layout.effective[c];
    const auto [user, guide] = commandParts(channels[c]);
    const bool command = p == Predictor::kCommand;
    if (!header.quantized) {
      double* column = values.get() + c * n;
      if (choices[c] != nullptr) {
        decodeChosenColumn(choices[c], words.get() + layout.slot[c] * n, kinematicsOf(layout, channels, c, values.get(), n), column, n);
      } else {
        decodeColumn<Doubles>(p, words.get() + layout.slot[c] * n, command ? values.get() + columnOf(channels, guide) * n : nullptr,
                              command ? values.get() + columnOf(channels, user) * n : nullptr, column, n);
      }
      continue;
    }
    decodeColumn<Steps>(p, words.get() + layout.slot[c] * n, command ? k.get() + columnOf(channels, guide) * n : nullptr,
                        command ? k.get() + columnOf(channels, user) * n : nullptr, k.get() + c * n, n);
    fromSteps(k.get() + c * n, layout.steps[c], values.get() + c * n, n);
  }
  return toSamples(values.get(), channels, n);
}

/// `samples` as an hsc2 block: the header, then its copy, the choices and the residuals in
/// their layouts as one zstd frame.
std::string encodeRevision2(std::span<const Sample> samples, std::span<const Channel> channels,
                            const ChannelResolution& resolution, int level) {
  const std::size_t n = samples.size();
  const std::size_t m = channels.size();
  const bool quantized = !resolution.empty();

  // The header: what the blob holds, and how each channel is predicted and laid out.
  std::string blob(kMagicV2, sizeof kMagicV2);
  put<std::uint32_t>(blob, static_cast<std::uint32_t>(n));
  put<std::uint16_t>(blob, static_cast<std::uint16_t>(m));
  put<std::uint8_t>(blob, quantized ? kQuantized : 0);
  put<std::uint8_t>(blob, 0);
  LayoutV2 layout = appendChannelEntries(blob, channels, resolution, quantized);

  // Each column as doubles (lossless) or whole steps; each sample read once.
  const auto values = columnsOf(samples, channels);
  const auto k = wholeStepsOf(values.get(), layout, channels, n, quantized);

  // The kinematic predictions' a and b, fitted to this trial, after the channels.
  appendKinematics(blob, layout, channels, values.get(), n);
  layout.header_bytes = blob.size();

  // Each column's residuals against its predictions, zigzagged; the chosen columns' choices.
  std::string content = blob;  // the header again, under zstd's checksum
  const auto words = appendChoicesAndResiduals(content, layout, channels, values.get(), k.get(), n, quantized);

  // Then the byte-plane channels' planes, the bit-length channels' lengths, and their bits.
  const std::array<std::size_t, 4> part_ends = appendResidualParts(content, layout, words.get(), n);

  // Compressed, with zstd's checksum of the content: a damaged block is refused, never read as
  // samples. Each part starts a zstd block of its own (the bits are incompressible and
  // are kept raw, the others get tables of their own). The thread keeps its context (and its
  // tables) from one trial to the next.
  put<std::uint64_t>(blob, content.size());
  blob += compressInParts(content, part_ends, level);
  return blob;
}

}  // namespace hattr::io::detail
