// Preprocessing (paper 5.1.1): normalization, time scaling, interpolation, and the whole
// chain, on hand-computed values and exact properties of linear data.

#include "hattr/analysis/preprocess.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "support/test_support.hpp"

namespace hattr::analysis {
namespace {

// ---- Normalization ---------------------------------------------------------------------------

// mean 3.25, range 6: (x - 3.25) / 6.
TEST(Normalize, PaperChoiceCentresOnTheMeanAndDividesByTheRange) {
  const std::vector<double> x{1.0, 2.0, 3.0, 7.0};
  const auto y = normalize(x, Normalization::kPaper);
  const std::vector<double> expected{-0.375, -1.25 / 6.0, -0.25 / 6.0, 0.625};
  ASSERT_EQ(y.size(), expected.size());
  for (std::size_t i = 0; i < y.size(); ++i) EXPECT_DOUBLE_EQ(y[i], expected[i]) << i;
}

// mean 5, sample variance 32 / 7.
TEST(Normalize, ZScoreUsesTheSampleStandardDeviation) {
  const std::vector<double> x{2, 4, 4, 4, 5, 5, 7, 9};
  const auto y = normalize(x, Normalization::kZScore);
  EXPECT_DOUBLE_EQ(y.back(), 4.0 / std::sqrt(32.0 / 7.0));
  EXPECT_DOUBLE_EQ(y.front(), -3.0 / std::sqrt(32.0 / 7.0));
}

TEST(Normalize, LeavesValuesAloneWithNoneAndZeroesAConstantSeries) {
  const std::vector<double> x{3.0, -1.0, 2.5};
  EXPECT_EQ(normalize(x, Normalization::kNone), x);
  const std::vector<double> flat{4.2, 4.2, 4.2};
  for (const auto how : {Normalization::kPaper, Normalization::kZScore}) {
    EXPECT_EQ(normalize(flat, how), (std::vector<double>{0.0, 0.0, 0.0}));
  }
  EXPECT_EQ(normalize(std::vector<double>{5.0}, Normalization::kZScore),
            (std::vector<double>{0.0}));
}

// Whatever the series, kPaper gives mean 0 and range 1, kZScore mean 0 and sd 1.
TEST(Normalize, GivesZeroMeanAndUnitRangeOrSdOnRandomSeries) {
  const std::uint64_t seed = test::testSeed(31);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> value(50.0, 20.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> x(2 + rng() % 100);
    for (double& v : x) v = value(rng);
    const auto paper = normalize(x, Normalization::kPaper);
    const auto z = normalize(x, Normalization::kZScore);
    double mean_p = 0.0, mean_z = 0.0, squares = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      mean_p += paper[i];
      mean_z += z[i];
      squares += z[i] * z[i];
    }
    const auto [lo, hi] = std::minmax_element(paper.begin(), paper.end());
    EXPECT_NEAR(mean_p / static_cast<double>(x.size()), 0.0, 1e-12) << "seed " << seed;
    EXPECT_NEAR(*hi - *lo, 1.0, 1e-12) << "seed " << seed;
    EXPECT_NEAR(mean_z / static_cast<double>(x.size()), 0.0, 1e-12) << "seed " << seed;
    EXPECT_NEAR(squares / static_cast<double>(x.size() - 1), 1.0, 1e-12) << "seed " << seed;
  }
}

// ---- Time scaling and interpolation ----------------------------------------------------------

// Trial 10..14 s (4 s) onto expert 0..1.5 s: factor 0.375.
TEST(TimeScale, MapsTheTrialSpanOntoTheExpertSpan) {
  const std::vector<double> trial{10.0, 11.0, 14.0};
  const std::vector<double> expert{0.0, 0.5, 1.0, 1.5};
  EXPECT_EQ(timeScale(trial, expert), (std::vector<double>{0.0, 0.375, 1.5}));
}

TEST(InterpolateAt, IsExactOnALinearFunctionAndHitsSamplesExactly) {
  const std::uint64_t seed = test::testSeed(32);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> gap(0.001, 0.1);
  std::vector<double> t{0.3};
  for (int i = 0; i < 50; ++i) t.push_back(t.back() + gap(rng));
  std::vector<double> v;
  for (const double ti : t) v.push_back(3.0 * ti - 1.0);
  std::uniform_real_distribution<double> when(t.front(), t.back());
  std::vector<double> queries{t.front(), t.back(), t[7]};
  for (int q = 0; q < 100; ++q) queries.push_back(when(rng));
  const auto out = interpolateAt(t, v, queries);
  EXPECT_EQ(out[0], v.front());
  EXPECT_EQ(out[1], v.back());
  EXPECT_EQ(out[2], v[7]);
  for (std::size_t q = 0; q < queries.size(); ++q) {
    EXPECT_NEAR(out[q], 3.0 * queries[q] - 1.0, 1e-12) << "seed " << seed << " query " << q;
  }
}

// Queries in order walk the segments; queries out of order search them: the same values.
TEST(InterpolateAt, GivesTheSameValueToAQueryInOrderOrOutOfIt) {
  const std::uint64_t seed = test::testSeed(33);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> gap(0.001, 0.1);
  std::vector<double> t{0.0};
  for (int i = 0; i < 200; ++i) t.push_back(t.back() + gap(rng));
  std::vector<double> v;
  for (const double ti : t) v.push_back(std::sin(7.0 * ti));
  std::uniform_real_distribution<double> when(t.front(), t.back());
  std::vector<double> sorted{t.front(), t[3], t[3], t.back()};
  for (int q = 0; q < 300; ++q) sorted.push_back(when(rng));
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> shuffled = sorted;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  const auto in_order = interpolateAt(t, v, sorted);
  const auto out_of_order = interpolateAt(t, v, shuffled);
  for (std::size_t q = 0; q < sorted.size(); ++q) {
    const double alone = interpolateAt(t, v, std::vector<double>{sorted[q]}).front();
    EXPECT_EQ(in_order[q], alone) << "seed " << seed << " query " << q;
  }
  for (std::size_t q = 0; q < shuffled.size(); ++q) {
    const double alone = interpolateAt(t, v, std::vector<double>{shuffled[q]}).front();
    EXPECT_EQ(out_of_order[q], alone) << "seed " << seed << " query " << q;
  }
}

// ---- The whole chain -------------------------------------------------------------------------

// A ramp v = 5 + 2 t over 2..6 s, irregularly sampled, onto expert times in 0..1 s:
// t = 2 + 4 e, so v = 9 + 8 e at expert time e.
TEST(PreprocessTrial, StretchesAndResamplesALinearTrialExactly) {
  const std::vector<double> trial_t{2.0, 2.3, 3.9, 4.0, 5.5, 6.0};
  std::vector<double> trial_v;
  for (const double t : trial_t) trial_v.push_back(5.0 + 2.0 * t);
  std::vector<double> expert_t;
  for (int k = 0; k <= 20; ++k) expert_t.push_back(0.05 * k);
  const auto out = preprocessTrial(trial_t, trial_v, expert_t, Normalization::kNone);
  ASSERT_EQ(out.size(), expert_t.size());
  for (std::size_t k = 0; k < out.size(); ++k) {
    EXPECT_NEAR(out[k], 9.0 + 8.0 * expert_t[k], 1e-12) << k;
  }
  // With kPaper the mean is that of the trial's own samples (before resampling) and the
  // range is 17 - 9 = 8.
  double mean = 0.0;
  for (const double v : trial_v) mean += v;
  mean /= static_cast<double>(trial_v.size());
  const auto paper = preprocessTrial(trial_t, trial_v, expert_t);
  EXPECT_NEAR(paper.front(), (9.0 - mean) / 8.0, 1e-12);
  EXPECT_NEAR(paper.back(), (17.0 - mean) / 8.0, 1e-12);
}

// The expert's own series played twice as slowly, starting later, comes back unchanged.
TEST(PreprocessTrial, UndoesAPureChangeOfSpeed) {
  std::vector<double> expert_t, expert_v, trial_t;
  for (int k = 0; k < 200; ++k) {
    expert_t.push_back(0.01 * k);
    expert_v.push_back(std::sin(7.0 * expert_t.back()));
    trial_t.push_back(3.0 + 2.0 * expert_t.back());
  }
  const auto out = preprocessTrial(trial_t, expert_v, expert_t, Normalization::kNone);
  for (std::size_t k = 0; k < out.size(); ++k) EXPECT_NEAR(out[k], expert_v[k], 1e-12) << k;
}

TEST(PreprocessTrial, RefusesBadSeriesSayingWhichAndWhere) {
  const std::vector<double> t{0.0, 0.1, 0.2};
  const std::vector<double> v{1.0, 2.0, 3.0};
  EXPECT_EQ(test::inputErrorOf([&] { (void)preprocessTrial({}, {}, t); }),
            "preprocessTrial: trial times: expected at least 2 time stamps, got 0");
  EXPECT_EQ(test::inputErrorOf([&] {
              (void)preprocessTrial(std::vector<double>{0.0, 0.1, 0.1}, v, t);
            }),
            "preprocessTrial: trial times[2]: expected strictly increasing time stamps, got 0.1 s "
            "after 0.1 s");
  EXPECT_EQ(test::inputErrorOf([&] {
              (void)preprocessTrial(t, std::vector<double>{1.0, 2.0}, t);
            }),
            "preprocessTrial: expected as many trial values as trial time stamps (3), got 2");
  EXPECT_EQ(test::inputErrorOf([&] {
              (void)preprocessTrial(t, std::vector<double>{1.0, std::nan(""), 3.0}, t);
            }),
            "preprocessTrial: trial values[1]: expected a finite number, got nan");
  EXPECT_EQ(test::inputErrorOf([&] { (void)preprocessTrial(t, v, std::vector<double>{1.0}); }),
            "preprocessTrial: expert times: expected at least 2 time stamps, got 1");
  EXPECT_EQ(test::inputErrorOf([&] {
              (void)interpolateAt(t, v, std::vector<double>{0.1, 0.25});
            }),
            "interpolateAt: query time [1]: expected a time within [0, 0.2] s, got 0.25");
  EXPECT_EQ(test::inputErrorOf([] { (void)normalize({}, Normalization::kPaper); }),
            "normalize: values: expected at least 1 value, got 0");
}

}  // namespace
}  // namespace hattr::analysis
