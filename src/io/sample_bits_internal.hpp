#pragma once
// The compact sample encoding's layouts of residuals before zstd (sample_bits.cpp): byte
// planes, and bit lengths with bits. Residuals are 64-bit words; bytes are little-endian.

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace hattr::io::detail {

static_assert(std::endian::native == std::endian::little, "the sample encoding is little-endian");

/// Bits appended least significant first, 64 at a time.
class BitWriter {
 public:
  explicit BitWriter(std::string& out) : out_(out) {}
  /// The low `count` bits of `bits` (count < 64).
  void put(std::uint64_t bits, int count) {
    if (count == 0) return;
    bits &= (std::uint64_t{1} << count) - 1;
    pending_ |= bits << filled_;
    if (filled_ + count < 64) {
      filled_ += count;
      return;
    }
    char word[8];
    std::memcpy(word, &pending_, 8);
    out_.append(word, 8);
    pending_ = filled_ == 0 ? 0 : bits >> (64 - filled_);
    filled_ = filled_ + count - 64;
  }
  /// Appends the bits not yet written, in as few bytes as hold them.
  void finish() {
    char word[8];
    std::memcpy(word, &pending_, 8);
    out_.append(word, static_cast<std::size_t>((filled_ + 7) / 8));
    pending_ = 0;
    filled_ = 0;
  }

 private:
  std::string& out_;
  std::uint64_t pending_ = 0;
  int filled_ = 0;  // always < 64
};

/// Reads what BitWriter wrote. The caller checks first that the bytes hold every bit it will
/// read.
class BitReader {
 public:
  explicit BitReader(std::string_view bytes) : bytes_(bytes) {}
  /// The next `count` bits (count < 64).
  std::uint64_t get(int count) {
    const std::size_t byte = position_ / 8;
    const auto shift = static_cast<int>(position_ % 8);
    std::uint64_t value = load(byte) >> shift;
    if (shift + count > 64) value |= load(byte + 8) << (64 - shift);
    position_ += static_cast<std::size_t>(count);
    return count == 0 ? 0 : value & ((std::uint64_t{1} << count) - 1);
  }
  /// True when every byte was read and the last one's unused bits are 0.
  bool atCleanEnd() const {
    if ((position_ + 7) / 8 != bytes_.size()) return false;
    return position_ % 8 == 0 || (static_cast<unsigned char>(bytes_.back()) >> (position_ % 8)) == 0;
  }

 private:
  /// Up to 8 bytes from `at`, those past the end read as 0.
  std::uint64_t load(std::size_t at) const {
    std::uint64_t word = 0;
    if (at < bytes_.size()) std::memcpy(&word, bytes_.data() + at, std::min<std::size_t>(8, bytes_.size() - at));
    return word;
  }

  std::string_view bytes_;
  std::size_t position_ = 0;  // in bits
};

/// Byte planes: byte b of every word, for b = 0..7 (smooth data leaves long runs in the
/// high planes).
void appendShuffled(std::string& out, const std::uint64_t* words, std::size_t n);

/// The words back from their byte planes (planes.size() / 8 of them).
void unshuffle(std::string_view planes, std::uint64_t* words);

/// Residuals as bit lengths and bits: each length as its change from the last one (a byte),
/// then, after every such channel's lengths, the bits below each residual's top bit (the top
/// bit is 1 by definition). This appends the lengths' changes.
void appendLengthChanges(std::string& out, const std::uint64_t* words, std::size_t n);

/// Appends the bits below each word's top bit.
void appendBitsBelowTop(BitWriter& bits, const std::uint64_t* words, std::size_t n);

/// The bit lengths of a column's residuals back from their changes, and how many bits follow.
/// Throws InputError naming channel `name` for a length above 64.
std::uint64_t readBitLengths(const unsigned char* changes, std::uint8_t* lengths, std::size_t n, std::string_view name);

/// The words back from their bit lengths and the bits below their top bits.
void readBits(BitReader& bits, const std::uint8_t* lengths, std::uint64_t* words, std::size_t n);

}  // namespace hattr::io::detail
