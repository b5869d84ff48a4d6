// The compact sample encoding's first revision, hsc1 (docs/study-store.md): a fixed predictor
// per channel, every residual in byte planes. What schema 4 first wrote; now only read.
// Compiled with -ffp-contract=off (src/CMakeLists.txt), as every file of the encoding that
// computes with doubles.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "hattr/core/channel.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/sample.hpp"
#include "sample_bits_internal.hpp"
#include "sample_codec_framing_internal.hpp"
#include "sample_codec_internal.hpp"
#include "sample_codec_predictors_internal.hpp"

namespace hattr::io::detail {
namespace {

/// hsc1: every continuous channel follows a quadratic.
Predictor predictorV1(Channel c, std::span<const Channel> channels) {
  return fixedOrChosen(c, channels, Predictor::kQuadratic);
}

}  // namespace

/// An hsc1 block: a fixed predictor per channel, every residual in byte planes.
std::vector<Sample> decodeRevision1(std::string_view blob, std::span<const Channel> channels, std::size_t count) {
  const BlockHeader header = readBlockHeader(blob, channels, count, kChannelBytesV1);
  const std::size_t n = header.n, m = header.m;
  std::vector<Predictor> predictors(m);
  std::vector<double> steps(m);
  for (std::size_t c = 0; c < m; ++c) {
    predictors[c] = predictorV1(channels[c], channels);
    steps[c] = readChannelEntry(blob, kHeaderBytes + c * kChannelBytesV1, c, channels[c], predictors[c], header.quantized, 2);
  }

  // The frame: the header's copy and the byte planes, under zstd's checksum.
  const std::size_t header_bytes = kHeaderBytes + m * kChannelBytesV1;
  const auto content_size = get<std::uint64_t>(blob, header_bytes);
  HATTR_THROW_UNLESS(content_size == header_bytes + n * m * 8,
                     "samples: the encoded block says {} bytes of header and residuals, expected {}", content_size,
                     header_bytes + n * m * 8);
  const auto content = decompressContent(blob, header_bytes, content_size);
  const auto words = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
  unshuffle(std::string_view(content.get() + header_bytes, n * m * 8), words.get());

  // Each column from its residuals and predictions, the commanded forces after their parts.
  const auto values = std::make_unique_for_overwrite<double[]>(n * m);
  const auto k = std::make_unique_for_overwrite<std::uint64_t[]>(header.quantized ? n * m : 0);
  for (const std::size_t c : decodingOrder(predictors)) {
    const auto [user, guide] = commandParts(channels[c]);
    if (!header.quantized) {
      const bool command = predictors[c] == Predictor::kCommand;
      decodeColumn<Doubles>(predictors[c], words.get() + c * n, command ? values.get() + columnOf(channels, guide) * n : nullptr,
                            command ? values.get() + columnOf(channels, user) * n : nullptr, values.get() + c * n, n);
      continue;
    }
    const Predictor p = stepPredictor(predictors[c], channels, steps, c);
    const bool command = p == Predictor::kCommand;
    decodeColumn<Steps>(p, words.get() + c * n, command ? k.get() + columnOf(channels, guide) * n : nullptr,
                        command ? k.get() + columnOf(channels, user) * n : nullptr, k.get() + c * n, n);
    fromSteps(k.get() + c * n, steps[c], values.get() + c * n, n);
  }
  return toSamples(values.get(), channels, n);
}

}  // namespace hattr::io::detail
