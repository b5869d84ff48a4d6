// DTW: hand-computed and analytic cases, seeded property tests against the plain
// full-matrix reference (on every instruction set the kernels were compiled for), early
// abandoning, warping paths, multivariate variants, batches and the cost matrix.

#include "hattr/analysis/dtw.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include "hattr/core/error.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::analysis {
namespace {

using ::testing::HasSubstr;

using test::kInf;
constexpr double kDtwRelTol = 1e-9;

std::string seedNote(std::uint64_t seed) {
  return fmt::format("seed {} (rerun with HATTR_TEST_SEED={})", seed, seed);
}

// A random walk of `n` points: smooth enough to warp, random enough to differ.
std::vector<double> randomWalk(std::mt19937_64& rng, std::size_t n) {
  std::normal_distribution<double> step(0.0, 1.0);
  std::vector<double> s(n);
  double x = step(rng);
  for (auto& v : s) v = x += step(rng);
  return s;
}

// A random problem: lengths 1..max_len, either cost function, a random band or none.
struct RandomCase {
  std::vector<double> a;
  std::vector<double> b;
  DtwOptions options;
};

RandomCase randomCase(std::mt19937_64& rng, std::size_t max_len) {
  RandomCase c;
  c.a = randomWalk(rng, 1 + rng() % max_len);
  c.b = randomWalk(rng, 1 + rng() % max_len);
  c.options.cost = rng() % 2 == 0 ? DtwCost::kAbsolute : DtwCost::kSquared;
  const auto pick = rng() % 4;
  c.options.band_fraction = pick == 0   ? -1.0
                            : pick == 1 ? 0.0
                                        : std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  return c;
}

void expectNear(double actual, double expected, const std::string& note) {
  EXPECT_NEAR(actual, expected, kDtwRelTol * std::max(1.0, std::abs(expected))) << note;
}

// ---- Hand-computed and analytic values ----------------------------------------------------

// a = (0, 1, 2), b = (0, 2). |a_i - b_j| = [[0, 2], [1, 1], [2, 0]];
// D = [[0, 2], [1, 1], [3, 1]] -> cost 1 along (0,0), (1,0), (2,1).
TEST(Dtw, MatchesAHandComputedExample) {
  const std::vector<double> a{0.0, 1.0, 2.0};
  const std::vector<double> b{0.0, 2.0};
  const DtwResult result = dtw(a, b, {.want_path = true});
  EXPECT_DOUBLE_EQ(result.cost, 1.0);
  EXPECT_EQ(result.path, (std::vector<WarpStep>{{0, 0}, {1, 0}, {2, 1}}));
  EXPECT_DOUBLE_EQ(dtwReference(a, b), 1.0);
  // Squared: costs [[0, 4], [1, 1], [4, 0]]; D = [[0, 4], [1, 1], [5, 1]].
  EXPECT_DOUBLE_EQ(dtwDistance(a, b, {.cost = DtwCost::kSquared}), 1.0);
}

TEST(Dtw, IsZeroForIdenticalSeries) {
  std::mt19937_64 rng(test::testSeed(1));
  for (const std::size_t n : {1, 2, 7, 333}) {
    const auto a = randomWalk(rng, n);
    EXPECT_EQ(dtwDistance(a, a), 0.0) << n;
    EXPECT_EQ(dtwDistance(a, a, {.cost = DtwCost::kSquared, .band_fraction = 0.0}), 0.0) << n;
    EXPECT_EQ(dtw(a, a, {.want_path = true}).cost, 0.0) << n;
  }
}

// A one-point series is matched with every point of the other.
TEST(Dtw, OfAOnePointSeriesIsTheSumOfCostsAgainstEveryPoint) {
  const std::vector<double> one{1.5};
  const std::vector<double> b{0.0, 1.0, 4.0, -2.0};
  EXPECT_DOUBLE_EQ(dtwDistance(one, b), 1.5 + 0.5 + 2.5 + 3.5);
  EXPECT_DOUBLE_EQ(dtwDistance(b, one, {.cost = DtwCost::kSquared}), 2.25 + 0.25 + 6.25 + 12.25);
}

// With a zero band and equal lengths only the main diagonal is allowed.
TEST(Dtw, WithAZeroBandOnEqualLengthsIsThePointwiseSum) {
  std::mt19937_64 rng(test::testSeed(2));
  const auto a = randomWalk(rng, 101);
  const auto b = randomWalk(rng, 101);
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += std::abs(a[i] - b[i]);
  expectNear(dtwDistance(a, b, {.band_fraction = 0.0}), sum, "zero band");
}

TEST(DtwBandRadius, FollowsTheFractionAndCoversTheLengthDifference) {
  EXPECT_EQ(dtwBandRadius(100, 100, 0.1), 10u);
  EXPECT_EQ(dtwBandRadius(100, 100, 0.101), 11u);  // ceil
  EXPECT_EQ(dtwBandRadius(100, 60, 0.1), 40u);     // at least |n - m|
  EXPECT_EQ(dtwBandRadius(100, 100, 0.0), 0u);
  EXPECT_EQ(dtwBandRadius(100, 100, 1.0), kNoBand);
  EXPECT_EQ(dtwBandRadius(100, 100, -0.5), kNoBand);
  EXPECT_THAT(test::inputErrorOf([] { (void)dtwBandRadius(3, 3, std::nan("")); }),
              HasSubstr("band_fraction: expected a number"));
}

// ---- Against the reference -----------------------------------------------------------------

TEST(Dtw, EqualsThePlainReferenceOnRandomSeries) {
  const std::uint64_t seed = test::testSeed(20261121);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 300; ++trial) {
    const RandomCase c = randomCase(rng, 70);
    const double expected = dtwReference(c.a, c.b, c.options);
    const std::string note = fmt::format("trial {} n {} m {} band {}", trial, c.a.size(),
                                         c.b.size(), c.options.band_fraction);
    expectNear(dtwDistance(c.a, c.b, c.options), expected, note);
    DtwOptions with_path = c.options;
    with_path.want_path = true;
    expectNear(dtw(c.a, c.b, with_path).cost, expected, note);
  }
}

// The same binary dispatches to AVX-512, AVX2, SSE4 ... at run time: check each one that
// this CPU can run.
TEST(Dtw, EqualsThePlainReferenceOnEveryCompiledInstructionSet) {
  const std::uint64_t seed = test::testSeed(5);
  SCOPED_TRACE(seedNote(seed));
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_EQ(dtwSimdTarget(), hwy::TargetName(target));
    std::mt19937_64 rng(seed);
    for (int trial = 0; trial < 40; ++trial) {
      const RandomCase c = randomCase(rng, 50);
      const std::string note = fmt::format("target {} trial {}", hwy::TargetName(target), trial);
      expectNear(dtwDistance(c.a, c.b, c.options), dtwReference(c.a, c.b, c.options), note);
    }
    std::vector<std::vector<double>> as, bs;
    for (int p = 0; p < 40; ++p) {
      as.push_back(randomWalk(rng, 30));
      bs.push_back(randomWalk(rng, 25));
    }
    const auto costs = dtwBatch(as, bs, {.band_fraction = 0.3});
    for (std::size_t p = 0; p < as.size(); ++p) {
      expectNear(costs[p], dtwReference(as[p], bs[p], {.band_fraction = 0.3}),
                 fmt::format("target {} batch pair {}", hwy::TargetName(target), p));
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

// Series longer than a stripe of the pair kernel (1024 rows, whose diagonals stay in L1): the
// stripes' costs are the unstriped reference's to the bit (absolute cost: no multiply to fuse),
// with and without a band, one channel or several, and abandoned exactly above a bound.
TEST(Dtw, LongSeriesInStripesEqualTheReferenceToTheBit) {
  const std::uint64_t seed = test::testSeed(62);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 6; ++trial) {
    const std::size_t n = 1025 + rng() % 1500;
    const std::size_t m = 1025 + rng() % 1500;
    const std::vector<double> a = randomWalk(rng, n);
    const std::vector<double> b = randomWalk(rng, m);
    const DtwOptions options{.band_fraction = trial % 2 == 0 ? -1.0 : 0.8};
    const std::string note = fmt::format("trial {} n {} m {} band {}", trial, n, m, options.band_fraction);
    const double expected = dtwReference(a, b, options);
    EXPECT_EQ(dtwDistance(a, b, options), expected) << note;
    // Abandoned above a bound below the cost (far below: a stripe's last row already exceeds
    // it; just below: only the corner does), the cost itself at the cost.
    DtwOptions bounded = options;
    bounded.abandon_above = expected * 0.3;
    EXPECT_EQ(dtwDistance(a, b, bounded), kInf) << note;
    bounded.abandon_above = expected * 0.999;
    EXPECT_EQ(dtwDistance(a, b, bounded), kInf) << note;
    bounded.abandon_above = expected;
    EXPECT_EQ(dtwDistance(a, b, bounded), expected) << note;
    // Several channels summed per cell.
    const std::vector<std::vector<double>> as{a, randomWalk(rng, n)};
    const std::vector<std::vector<double>> bs{b, randomWalk(rng, m)};
    EXPECT_EQ(dtwDependent(as, bs, options).cost, dtwDependentReference(as, bs, options)) << note;
  }
  // On every instruction set compiled in that this CPU runs.
  const std::vector<double> a = randomWalk(rng, 1100);
  const std::vector<double> b = randomWalk(rng, 1300);
  const double expected = dtwReference(a, b, {});
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_EQ(dtwDistance(a, b, {}), expected) << hwy::TargetName(target);
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(Dtw, IsSymmetricForEqualLengthSeries) {
  const std::uint64_t seed = test::testSeed(3);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 100; ++trial) {
    const std::size_t n = 1 + rng() % 80;
    const auto a = randomWalk(rng, n);
    const auto b = randomWalk(rng, n);
    const DtwOptions options{.cost = trial % 2 == 0 ? DtwCost::kAbsolute : DtwCost::kSquared,
                             .band_fraction = trial % 3 == 0 ? -1.0 : 0.2};
    expectNear(dtwDistance(a, b, options), dtwDistance(b, a, options),
               fmt::format("trial {}", trial));
  }
}

TEST(Dtw, WithABandOfFullWidthEqualsNoBand) {
  const std::uint64_t seed = test::testSeed(4);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 100; ++trial) {
    const auto a = randomWalk(rng, 1 + rng() % 60);
    const auto b = randomWalk(rng, 1 + rng() % 60);
    EXPECT_EQ(dtwDistance(a, b, {.band_fraction = 1.0}), dtwDistance(a, b)) << trial;
    // A band as wide as the longer series excludes nothing either.
    EXPECT_EQ(dtwDistance(a, b, {.band_fraction = 0.999999}), dtwDistance(a, b)) << trial;
  }
}

// Narrowing the band removes paths, so the cost can only grow.
TEST(Dtw, NeverCostsLessWithANarrowerBand) {
  const std::uint64_t seed = test::testSeed(6);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 50; ++trial) {
    const auto a = randomWalk(rng, 20 + rng() % 60);
    const auto b = randomWalk(rng, 20 + rng() % 60);
    double previous = dtwDistance(a, b);
    for (const double fraction : {0.5, 0.3, 0.1, 0.0}) {
      const double cost = dtwDistance(a, b, {.band_fraction = fraction});
      EXPECT_GE(cost, previous) << "trial " << trial << " fraction " << fraction;
      previous = cost;
    }
  }
}

// ---- Early abandoning ------------------------------------------------------------------------

TEST(Dtw, AbandonsExactlyWhenTheCostExceedsTheBound) {
  const std::uint64_t seed = test::testSeed(7);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 100; ++trial) {
    RandomCase c = randomCase(rng, 60);
    const double truth = dtwReference(c.a, c.b, c.options);
    for (const double factor : {0.0, 0.3, 0.9, 1.0, 1.1, 3.0}) {
      c.options.abandon_above = truth * factor;
      const std::string note = fmt::format("trial {} factor {}", trial, factor);
      // truth * 1.0 == truth: the bound is not exceeded and the exact cost comes back.
      const bool exceeded = truth > c.options.abandon_above;
      for (const bool path : {false, true}) {
        c.options.want_path = path;
        const DtwResult result = dtw(c.a, c.b, c.options);
        if (exceeded) {
          EXPECT_EQ(result.cost, kInf) << note;
          EXPECT_TRUE(result.path.empty()) << note;
        } else {
          expectNear(result.cost, truth, note);
        }
      }
      c.options.want_path = false;
    }
  }
}

TEST(DtwBatch, AbandonsEachPairOnItsOwn) {
  const std::uint64_t seed = test::testSeed(8);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> as, bs;
  for (int p = 0; p < 50; ++p) {
    as.push_back(randomWalk(rng, 40));
    bs.push_back(randomWalk(rng, 45));
  }
  std::vector<double> truth;
  for (std::size_t p = 0; p < as.size(); ++p) truth.push_back(dtwReference(as[p], bs[p]));
  std::vector<double> sorted = truth;
  std::sort(sorted.begin(), sorted.end());
  for (const double bound : {0.0, sorted[10], sorted[25], sorted.back(), kInf}) {
    const auto costs = dtwBatch(as, bs, {.abandon_above = bound});
    for (std::size_t p = 0; p < as.size(); ++p) {
      if (truth[p] > bound) {
        EXPECT_EQ(costs[p], kInf) << "pair " << p << " bound " << bound;
      } else {
        expectNear(costs[p], truth[p], fmt::format("pair {} bound {}", p, bound));
      }
    }
  }
}

// ---- Warping paths --------------------------------------------------------------------------

TEST(Dtw, PathRunsCornerToCornerInUnitStepsAndItsCostsSumToTheCost) {
  const std::uint64_t seed = test::testSeed(9);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 150; ++trial) {
    RandomCase c = randomCase(rng, 60);
    c.options.want_path = true;
    const DtwResult result = dtw(c.a, c.b, c.options);
    const std::size_t radius = dtwBandRadius(c.a.size(), c.b.size(), c.options.band_fraction);
    ASSERT_FALSE(result.path.empty());
    EXPECT_EQ(result.path.front(), (WarpStep{0, 0})) << trial;
    EXPECT_EQ(result.path.back(), (WarpStep{c.a.size() - 1, c.b.size() - 1})) << trial;
    double sum = 0.0;
    for (std::size_t s = 0; s < result.path.size(); ++s) {
      const WarpStep step = result.path[s];
      const double diff = c.a[step.i] - c.b[step.j];
      sum += c.options.cost == DtwCost::kAbsolute ? std::abs(diff) : diff * diff;
      const std::size_t gap = step.i > step.j ? step.i - step.j : step.j - step.i;
      if (radius != kNoBand) {
        EXPECT_LE(gap, radius) << "trial " << trial << " step " << s;
      }
      if (s == 0) continue;
      const WarpStep before = result.path[s - 1];
      const std::size_t di = step.i - before.i;
      const std::size_t dj = step.j - before.j;
      EXPECT_TRUE((di == 1 && dj == 0) || (di == 0 && dj == 1) || (di == 1 && dj == 1))
          << "trial " << trial << " step " << s;
    }
    expectNear(sum, result.cost, fmt::format("trial {}", trial));
  }
}

// ---- Input errors --------------------------------------------------------------------------

TEST(Dtw, RefusesEmptyAndNonFiniteSeriesSayingWhereAndWhat) {
  const std::vector<double> ok{1.0, 2.0};
  const std::vector<double> empty;
  const std::vector<double> with_nan{1.0, 2.0, std::nan("")};
  EXPECT_EQ(test::inputErrorOf([&] { (void)dtwDistance(empty, ok); }),
            "dtw: series a is empty: expected at least 1 value, got 0");
  EXPECT_EQ(test::inputErrorOf([&] { (void)dtw(ok, with_nan, {.want_path = true}); }),
            "dtw: series b at index 2: expected a finite number, got nan");
  EXPECT_THAT(test::inputErrorOf([&] { (void)dtwDistance(ok, ok, {.abandon_above = std::nan("")}); }),
              HasSubstr("abandon_above: expected a number or +infinity, got NaN"));
  const std::vector<std::vector<double>> two{ok, ok};
  const std::vector<std::vector<double>> ragged{ok, {1.0}};
  EXPECT_EQ(test::inputErrorOf([&] { (void)dtwDependent(two, ragged); }),
            "dtwDependent: series b channel 1: expected 2 values like channel 0, got 1");
  EXPECT_EQ(test::inputErrorOf([&] { (void)dtwIndependent(two, std::vector<std::vector<double>>{ok}); }),
            "dtwIndependent: expected the same number of channels in both series, got 2 and 1");
  EXPECT_EQ(test::inputErrorOf([&] { (void)dtwBatch(two, std::vector<std::vector<double>>{ok}); }),
            "dtwBatch: expected as many series in a as in b, got 2 and 1");
  EXPECT_EQ(test::inputErrorOf([&] { (void)dtwCostMatrix(two, {}, 0); }),
            "dtwCostMatrix: threads: expected at least 1, got 0");
  const std::vector<std::vector<double>> bad_third{ok, ok, with_nan};
  EXPECT_EQ(test::inputErrorOf([&] { (void)dtwCostMatrix(bad_third); }),
            "dtwCostMatrix: series 2 at index 2: expected a finite number, got nan");
}

// ---- Multivariate ---------------------------------------------------------------------------

std::vector<std::vector<double>> randomChannels(std::mt19937_64& rng, std::size_t channels,
                                                std::size_t n) {
  std::vector<std::vector<double>> s;
  for (std::size_t c = 0; c < channels; ++c) s.push_back(randomWalk(rng, n));
  return s;
}

TEST(DtwDependent, EqualsThePlainReferenceOnRandomSeries) {
  const std::uint64_t seed = test::testSeed(10);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 100; ++trial) {
    const std::size_t channels = 1 + rng() % 4;
    const auto a = randomChannels(rng, channels, 1 + rng() % 50);
    const auto b = randomChannels(rng, channels, 1 + rng() % 50);
    DtwOptions options{.cost = trial % 2 == 0 ? DtwCost::kAbsolute : DtwCost::kSquared,
                       .band_fraction = trial % 3 == 0 ? -1.0 : 0.25};
    const double expected = dtwDependentReference(a, b, options);
    const std::string note = fmt::format("trial {} channels {}", trial, channels);
    expectNear(dtwDependent(a, b, options).cost, expected, note);
    options.want_path = true;
    const DtwResult with_path = dtwDependent(a, b, options);
    expectNear(with_path.cost, expected, note);
    // The path's summed multichannel costs give the cost.
    double sum = 0.0;
    for (const WarpStep step : with_path.path) {
      for (std::size_t c = 0; c < channels; ++c) {
        const double diff = a[c][step.i] - b[c][step.j];
        sum += options.cost == DtwCost::kAbsolute ? std::abs(diff) : diff * diff;
      }
    }
    expectNear(sum, expected, note);
  }
}

TEST(DtwDependent, WithOneChannelEqualsUnivariateDtw) {
  std::mt19937_64 rng(test::testSeed(11));
  const auto a = randomChannels(rng, 1, 70);
  const auto b = randomChannels(rng, 1, 50);
  EXPECT_EQ(dtwDependent(a, b).cost, dtwDistance(a[0], b[0]));
}

// Dependent DTW shares one path, so it can never beat the channels warped on their own.
TEST(DtwIndependent, SumsPerChannelCostsAndNeverExceedsDependentDtw) {
  const std::uint64_t seed = test::testSeed(12);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 50; ++trial) {
    const auto a = randomChannels(rng, 3, 5 + rng() % 40);
    const auto b = randomChannels(rng, 3, 5 + rng() % 40);
    const auto per_channel = dtwIndependent(a, b);
    ASSERT_EQ(per_channel.size(), 3u);
    double sum = 0.0;
    for (std::size_t c = 0; c < 3; ++c) {
      expectNear(per_channel[c], dtwReference(a[c], b[c]), fmt::format("channel {}", c));
      sum += per_channel[c];
    }
    expectNear(dtwIndependentSum(a, b), sum, fmt::format("trial {}", trial));
    EXPECT_LE(sum, dtwDependent(a, b).cost * (1 + kDtwRelTol)) << trial;
    // Abandoning applies to the sum.
    EXPECT_EQ(dtwIndependentSum(a, b, {.abandon_above = 0.99 * sum}), kInf) << trial;
    expectNear(dtwIndependentSum(a, b, {.abandon_above = sum}), sum,
               fmt::format("trial {}", trial));
  }
}

// ---- Batches and cost matrices --------------------------------------------------------------

TEST(DtwBatch, EqualsTheReferenceAcrossStripEdgesBandsAndBounds) {
  // The batch kernel computes D in strips of rows: lengths below, at and around a strip's
  // height, the band's edges crossing strips, and a bound that abandons some pairs.
  const std::uint64_t seed = test::testSeed(21);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (const auto& [n, m] : std::vector<std::pair<std::size_t, std::size_t>>{
           {1, 1}, {1, 5}, {5, 1}, {3, 3}, {15, 16}, {16, 16}, {17, 9}, {33, 40}, {70, 64}}) {
    std::vector<std::vector<double>> as, bs;
    for (int p = 0; p < 37; ++p) {
      as.push_back(randomWalk(rng, n));
      bs.push_back(randomWalk(rng, m));
    }
    for (const DtwOptions& options :
         {DtwOptions{}, DtwOptions{.band_fraction = 0.0}, DtwOptions{.band_fraction = 0.15},
          DtwOptions{.cost = DtwCost::kSquared, .band_fraction = 0.4}}) {
      std::vector<double> truth;
      for (std::size_t p = 0; p < as.size(); ++p) truth.push_back(dtwReference(as[p], bs[p], options));
      std::vector<double> sorted = truth;
      std::sort(sorted.begin(), sorted.end());
      // A bound between two pairs' costs (the reference may round differently in the last bit).
      const double between = 0.5 * (sorted[sorted.size() / 2] + sorted[sorted.size() / 2 + 1]);
      for (const double bound : {kInf, between}) {
        DtwOptions bounded = options;
        bounded.abandon_above = bound;
        const auto costs = dtwBatch(as, bs, bounded);
        for (std::size_t p = 0; p < as.size(); ++p) {
          const std::string note = fmt::format("{}x{} band {} bound {} pair {}", n, m, options.band_fraction, bound, p);
          if (truth[p] > bound) {
            EXPECT_EQ(costs[p], kInf) << note;
          } else {
            expectNear(costs[p], truth[p], note);
          }
        }
      }
    }
  }
}

TEST(DtwBatch, EqualsPairByPairCostsForEqualAndMixedLengths) {
  const std::uint64_t seed = test::testSeed(13);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (const bool mixed : {false, true}) {
    std::vector<std::vector<double>> as, bs;
    for (int p = 0; p < 45; ++p) {
      as.push_back(randomWalk(rng, mixed ? 1 + rng() % 40 : 33));
      bs.push_back(randomWalk(rng, mixed ? 1 + rng() % 40 : 20));
    }
    for (const DtwOptions options :
         {DtwOptions{}, DtwOptions{.cost = DtwCost::kSquared, .band_fraction = 0.1}}) {
      const auto costs = dtwBatch(as, bs, options);
      ASSERT_EQ(costs.size(), as.size());
      for (std::size_t p = 0; p < as.size(); ++p) {
        expectNear(costs[p], dtwReference(as[p], bs[p], options),
                   fmt::format("mixed {} pair {}", mixed, p));
      }
    }
  }
  EXPECT_TRUE(dtwBatch(std::vector<std::vector<double>>{}, std::vector<std::vector<double>>{}).empty());
}

// A copy of `a` warped in time (by up to `warp` of its length, smoothly) plus noise: as a
// trial is to the expert, similar enough that the batch kernel prunes most cells.
std::vector<double> warpedCopy(std::mt19937_64& rng, const std::vector<double>& a, std::size_t m, double warp) {
  std::normal_distribution<double> noise(0.0, 0.3);
  const double phase = std::uniform_real_distribution<double>(0.0, 6.28)(rng);
  std::vector<double> b(m);
  const double last = static_cast<double>(a.size() - 1);
  for (std::size_t j = 0; j < m; ++j) {
    const double u = m == 1 ? 0.0 : static_cast<double>(j) / static_cast<double>(m - 1);
    const double t = std::clamp(u + warp * std::sin(3.14159 * u) * std::sin(phase + 2.0 * u), 0.0, 1.0) * last;
    const auto i = static_cast<std::size_t>(t);
    const double frac = t - static_cast<double>(i);
    b[j] = a[i] + (i + 1 < a.size() ? frac * (a[i + 1] - a[i]) : 0.0) + noise(rng);
  }
  return b;
}

// The batch kernel skips the cells that cannot be on the best path (pruned DTW): on similar
// series, where it skips most, and on dissimilar ones, with and without a band, the costs
// are those of the pair-by-pair kernel to the bit (absolute costs: no rounding differs), and
// the reference's for squared ones.
TEST(DtwBatch, PruningLeavesEveryCostAsComputedInFull) {
  HATTR_STARTS_NO_THREAD();
  const std::uint64_t seed = test::testSeed(23);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (const auto& [n, m] : std::vector<std::pair<std::size_t, std::size_t>>{{40, 40}, {300, 300}, {257, 311}, {600, 480}, {100, 300}, {300, 90}}) {
    for (const double warp : {0.02, 0.15, -1.0}) {  // -1: unrelated series
      std::vector<std::vector<double>> as, bs;
      for (int p = 0; p < 40; ++p) {
        as.push_back(randomWalk(rng, n));
        bs.push_back(warp < 0.0 ? randomWalk(rng, m) : warpedCopy(rng, as.back(), m, warp));
      }
      for (const double band : {-1.0, 0.3}) {
        const std::string note = fmt::format("{}x{} warp {} band {}", n, m, warp, band);
        const DtwOptions absolute{.band_fraction = band};
        const auto costs = dtwBatch(as, bs, absolute);
        for (std::size_t p = 0; p < as.size(); ++p) {
          EXPECT_EQ(costs[p], dtwDistance(as[p], bs[p], absolute)) << note << " pair " << p;
        }
        const DtwOptions squared{.cost = DtwCost::kSquared, .band_fraction = band};
        const auto squared_costs = dtwBatch(as, bs, squared);
        for (std::size_t p = 0; p < as.size(); p += 7) {
          expectNear(squared_costs[p], dtwReference(as[p], bs[p], squared), fmt::format("{} squared pair {}", note, p));
        }
      }
    }
  }
}

TEST(DtwBatch, GivesTheSameCostsToTheBitOnAnyNumberOfThreads) {
  const std::uint64_t seed = test::testSeed(17);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (const bool mixed : {false, true}) {
    std::vector<std::vector<double>> as, bs;
    for (int p = 0; p < 77; ++p) {  // not a whole number of SIMD blocks; mixed: only the last pairs differ
      as.push_back(randomWalk(rng, mixed && p > 70 ? 1 + rng() % 60 : 50));
      bs.push_back(randomWalk(rng, mixed && p > 70 ? 1 + rng() % 60 : 41));
    }
    const auto one_thread = dtwBatch(as, bs);
    for (const unsigned threads : {2u, 3u, 4u, 200u}) {
      EXPECT_EQ(dtwBatch(as, bs, {}, threads), one_thread) << "mixed " << mixed << ", " << threads << " threads";
    }
    // The same over spans of the caller's memory (Python's arrays).
    const std::vector<std::span<const double>> a_spans(as.begin(), as.end()), b_spans(bs.begin(), bs.end());
    EXPECT_EQ(dtwBatch(a_spans, b_spans, {}, 3), one_thread) << "mixed " << mixed << ", spans";
  }
  const std::vector<std::vector<double>> none;
  EXPECT_THROW((void)dtwBatch(none, none, {}, 0), InputError);
}

TEST(DtwCostMatrix, IsSymmetricWithAZeroDiagonalAndHoldsThePairCosts) {
  const std::uint64_t seed = test::testSeed(14);
  SCOPED_TRACE(seedNote(seed));
  std::mt19937_64 rng(seed);
  for (const bool mixed : {false, true}) {
    std::vector<std::vector<double>> series;
    for (int s = 0; s < 21; ++s) series.push_back(randomWalk(rng, mixed ? 10 + rng() % 30 : 30));
    const Eigen::MatrixXd two = dtwCostMatrix(series, {}, 2);
    const Eigen::MatrixXd one = dtwCostMatrix(series, {}, 1);
    ASSERT_EQ(two.rows(), 21);
    ASSERT_EQ(two.cols(), 21);
    EXPECT_EQ(two, one);
    for (Eigen::Index i = 0; i < two.rows(); ++i) {
      EXPECT_EQ(two(i, i), 0.0);
      for (Eigen::Index j = i + 1; j < two.cols(); ++j) {
        EXPECT_EQ(two(i, j), two(j, i));
        expectNear(
            two(i, j),
            dtwReference(series[static_cast<std::size_t>(i)], series[static_cast<std::size_t>(j)]),
            fmt::format("mixed {} ({}, {})", mixed, i, j));
      }
    }
  }
  EXPECT_EQ(dtwCostMatrix({}).size(), 0);
}

}  // namespace
}  // namespace hattr::analysis
