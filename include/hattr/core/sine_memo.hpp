#pragma once
/// std::sin of the last angle asked, remembered: the servo tick asks the sine of the pen's
/// altitude several times a tick (the hand at every sub-step, the paper), and the altitude
/// changes seldom. The value is std::sin's, to the bit.

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace hattr {

class SineMemo {
 public:
  /// sin(angle_rad), computed only when the angle differs in any bit from the last one
  /// (so -0 and +0 are told apart, and a NaN is never remembered as its own answer).
  [[nodiscard]] double of(double angle_rad) noexcept {
    const auto bits = std::bit_cast<std::uint64_t>(angle_rad);
    if (bits != angle_bits_ || std::isnan(angle_rad)) {
      angle_bits_ = bits;
      sine_ = std::sin(angle_rad);
    }
    return sine_;
  }

 private:
  // Starts as a NaN's bits: the first call always computes.
  std::uint64_t angle_bits_ = std::bit_cast<std::uint64_t>(std::numeric_limits<double>::quiet_NaN());
  double sine_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace hattr
