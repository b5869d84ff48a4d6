// The compact sample encoding's layouts of residuals before zstd (sample_bits_internal.hpp):
// byte planes, and bit lengths with bits. No floating point here.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "hattr/core/error.hpp"
#include "sample_bits_internal.hpp"

namespace hattr::io::detail {

// ---- Layouts: byte planes, and bit lengths with bits ------------------------------------

/// Byte planes: byte b of every word, for b = 0..7 (smooth data leaves long runs in the
/// high planes).
void appendShuffled(std::string& out, const std::uint64_t* words, std::size_t n) {
  const std::size_t at = out.size();
  out.resize(at + n * 8);
  char* planes = out.data() + at;
  for (std::size_t w = 0; w < n; ++w) {
    for (std::size_t b = 0; b < 8; ++b) planes[b * n + w] = static_cast<char>(words[w] >> (8 * b));
  }
}

/// The words back from their byte planes.
void unshuffle(std::string_view planes, std::uint64_t* words) {
  const std::size_t n = planes.size() / 8;
  const auto* bytes = reinterpret_cast<const unsigned char*>(planes.data());
  for (std::size_t w = 0; w < n; ++w) {
    std::uint64_t word = 0;
    for (std::size_t b = 0; b < 8; ++b) word |= static_cast<std::uint64_t>(bytes[b * n + w]) << (8 * b);
    words[w] = word;
  }
}

/// Residuals as bit lengths and bits: each length as its change from the last one (a byte),
/// then, after every such channel's lengths, the bits below each residual's top bit (the top
/// bit is 1 by definition).
void appendLengthChanges(std::string& out, const std::uint64_t* words, std::size_t n) {
  const std::size_t at = out.size();
  out.resize(at + n);
  int last = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto length = static_cast<int>(std::bit_width(words[i]));
    out[at + i] = static_cast<char>(static_cast<std::uint8_t>(length - last));
    last = length;
  }
}

/// The bits below each word's top bit.
void appendBitsBelowTop(BitWriter& bits, const std::uint64_t* words, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const auto length = static_cast<int>(std::bit_width(words[i]));
    if (length > 1) bits.put(words[i], length - 1);
  }
}

/// The bit lengths of a column's residuals back from their changes, and how many bits follow.
std::uint64_t readBitLengths(const unsigned char* changes, std::uint8_t* lengths, std::size_t n, std::string_view name) {
  int last = 0;
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    last = static_cast<std::uint8_t>(last + changes[i]);
    HATTR_THROW_UNLESS(last <= 64, "samples: channel {}, sample {}: a residual of {} bits, expected at most 64 (damaged)",
                       name, i, last);
    lengths[i] = static_cast<std::uint8_t>(last);
    total += last > 1 ? static_cast<std::uint64_t>(last - 1) : 0;
  }
  return total;
}

/// The words back from their bit lengths and the bits below their top bits.
void readBits(BitReader& bits, const std::uint8_t* lengths, std::uint64_t* words, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const int length = lengths[i];
    words[i] = length == 0 ? 0 : (std::uint64_t{1} << (length - 1)) | bits.get(length - 1);
  }
}

}  // namespace hattr::io::detail
