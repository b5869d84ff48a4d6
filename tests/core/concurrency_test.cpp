#include <algorithm>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "hattr/core/histogram.hpp"
#include "hattr/core/spsc_ring.hpp"
#include "hattr/core/triple_buffer.hpp"
#include "support/test_support.hpp"

namespace hattr {
namespace {

TEST(SpscRing, KeepsOrderAndRefusesWhenFull) {
  SpscRing<int> ring(4);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.tryPush(i));
  EXPECT_FALSE(ring.tryPush(99));
  int value = -1;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(ring.tryPop(value));
    EXPECT_EQ(value, i);
  }
  EXPECT_FALSE(ring.tryPop(value));
}

TEST(SpscRing, RejectsACapacityThatIsNotAPowerOfTwo) { EXPECT_THROW(SpscRing<int>(6), InvariantError); }

TEST(SpscRing, DeliversEveryItemInOrderAcrossThreads) {
  constexpr std::uint64_t kItems = 200'000;
  SpscRing<std::uint64_t> ring(256);
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems;) {
      if (ring.tryPush(i)) ++i;
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t value = 0;
  while (expected < kItems) {
    if (ring.tryPop(value)) {
      ASSERT_EQ(value, expected);
      ++expected;
    }
  }
  producer.join();
}

struct Triple {
  std::uint64_t a = 0, b = 0, c = 0;
};

TEST(TripleBuffer, ReaderSeesWholeValuesThatNeverGoBackward) {
  TripleBuffer<Triple> buffer;
  constexpr std::uint64_t kWrites = 200'000;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= kWrites; ++i) buffer.write({i, 2 * i, 3 * i});
    done = true;
  });
  Triple seen;
  std::uint64_t last = 0;
  while (!done.load() || last < kWrites) {
    buffer.read(seen);
    ASSERT_EQ(seen.b, 2 * seen.a);
    ASSERT_EQ(seen.c, 3 * seen.a);
    ASSERT_GE(seen.a, last);
    last = seen.a;
    if (done.load()) {
      buffer.read(seen);
      last = seen.a;
      break;
    }
  }
  writer.join();
  buffer.read(seen);
  EXPECT_EQ(seen.a, kWrites);
}

TEST(DurationHistogram, PercentilesAreWithinItsResolutionOfTheExactOnes) {
  const std::uint64_t seed = test::testSeed(42);
  std::mt19937_64 rng(seed);
  std::lognormal_distribution<double> dist(9.0, 1.5);  // around 8 µs, long tail
  DurationHistogram histogram;
  std::vector<std::int64_t> values;
  for (int i = 0; i < 100'000; ++i) {
    const auto v = static_cast<std::int64_t>(dist(rng));
    values.push_back(v);
    histogram.record(v);
  }
  std::sort(values.begin(), values.end());
  for (double q : {0.5, 0.99, 0.999}) {
    const auto exact = static_cast<double>(values[static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size()))) - 1]);
    const auto got = histogram.percentile_ns(q);
    EXPECT_GE(static_cast<double>(got), exact) << "q=" << q << " seed " << seed;
    EXPECT_LE(static_cast<double>(got), exact * (1.0 + 1.0 / 32) + 1) << "q=" << q << " seed " << seed;
  }
  EXPECT_EQ(histogram.max_ns(), values.back());
  EXPECT_EQ(histogram.percentile_ns(1.0), values.back());
  EXPECT_EQ(histogram.count(), 100'000u);
}

}  // namespace
}  // namespace hattr
