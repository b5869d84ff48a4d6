// SineMemo: std::sin's value to the bit, for whatever angle is asked last.

#include "hattr/core/sine_memo.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <gtest/gtest.h>

namespace hattr {
namespace {

std::uint64_t bitsOf(double x) { return std::bit_cast<std::uint64_t>(x); }

TEST(SineMemo, GivesStdSinsBitsForEachNewAngleAndTheLastOneAgain) {
  SineMemo memo;
  for (const double angle : {1.0471975511965976, 1.0471975511965976, 0.1, 1.5707963267948966, 0.1, -2.5, 1e-300}) {
    EXPECT_EQ(bitsOf(memo.of(angle)), bitsOf(std::sin(angle))) << angle;
  }
}

// -0 and +0 compare equal but their sines differ in sign: the memo tells them apart by bits.
TEST(SineMemo, TellsNegativeZeroFromZero) {
  SineMemo memo;
  EXPECT_FALSE(std::signbit(memo.of(0.0)));
  EXPECT_TRUE(std::signbit(memo.of(-0.0)));
  EXPECT_FALSE(std::signbit(memo.of(0.0)));
}

TEST(SineMemo, ANanAngleGivesNanAndIsNotKept) {
  SineMemo memo;
  EXPECT_TRUE(std::isnan(memo.of(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_EQ(memo.of(0.5), std::sin(0.5));
}

}  // namespace
}  // namespace hattr
