// Learning-curve fits against R's nls() (tests/analysis/learning_curve_reference.R prints
// every literal below; R 4.2.2; the tests do not need R): the exponential and the power law
// of practice on 11 seeded scores, estimates, standard errors and 95 % intervals
// estimate ± qt(0.975, 8) × SE. nls stops at a relative offset of 1e-7, so the agreement
// asked is 1e-5 relative.

#include "hattr/analysis/learning_curve.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"

namespace hattr::analysis {
namespace {

const std::vector<double> kTrials{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
const std::vector<double> kScores{8.343, 6.087, 5.07, 4.258, 3.581, 3.016, 3.113, 2.494, 2.869, 2.241, 2.507};

struct Row {
  double estimate, se, lower, upper;
};

void expectParameter(const CurveParameter& p, const Row& r, const char* name) {
  const auto near = [](double a, double b) { return std::abs(a - b) <= 1e-5 * std::abs(b); };
  EXPECT_TRUE(near(p.estimate, r.estimate)) << name << " " << p.estimate << " vs R " << r.estimate;
  EXPECT_TRUE(near(p.std_error, r.se)) << name << " se " << p.std_error << " vs R " << r.se;
  EXPECT_TRUE(near(p.lower, r.lower)) << name << " lower " << p.lower << " vs R " << r.lower;
  EXPECT_TRUE(near(p.upper, r.upper)) << name << " upper " << p.upper << " vs R " << r.upper;
}

TEST(LearningCurve, ExponentialFitEqualsRsNls) {
  const CurveFit fit = fitLearningCurve(kTrials, kScores, CurveLaw::kExponential);
  EXPECT_NEAR(fit.rss, 0.34757576387880551, 1e-9);
  EXPECT_NEAR(fit.sigma, 0.20843936884583653, 1e-8);
  expectParameter(fit.asymptote, {2.3435944759385272, 0.1450651638265551, 2.0090736082804215, 2.6781153435966329}, "a");
  expectParameter(fit.amplitude, {5.9069430795866431, 0.20914756612100405, 5.4246479272437211, 6.3892382319295651}, "b");
  expectParameter(fit.rate, {0.39697404057698199, 0.036602463402744721, 0.31256860861159352, 0.48137947254237046}, "c");
  EXPECT_TRUE(fit.note.empty());
  EXPECT_NEAR(fit.at(1.0), fit.asymptote.estimate + fit.amplitude.estimate, 1e-12);
}

TEST(LearningCurve, PowerFitEqualsRsNls) {
  const CurveFit fit = fitLearningCurve(kTrials, kScores, CurveLaw::kPower);
  EXPECT_NEAR(fit.rss, 0.41878115643308073, 1e-9);
  expectParameter(fit.asymptote, {-1.8692713369513438, 1.8698922541417897, -6.1812506073885496, 2.4427079334858623}, "a");
  expectParameter(fit.amplitude, {10.267701383516217, 1.7789328130355166, 6.1654749604059358, 14.369927806626498}, "b");
  expectParameter(fit.rate, {0.38039389381848737, 0.10842973749844748, 0.1303544707679653, 0.6304333168690095}, "c");
}

TEST(LearningCurve, FlatScoresPutTheRateOnItsBoundAndSaySo) {
  const std::vector<double> flat{3.0, 3.1, 2.9, 3.0, 3.05, 2.95};
  const std::vector<double> n{1, 2, 3, 4, 5, 6};
  const CurveFit fit = fitLearningCurve(n, flat, CurveLaw::kExponential);
  EXPECT_FALSE(fit.note.empty());
}

// The report's slope over the recall trials and the trend with its interval are one function.
TEST(LinearTrend, TwoPointsGiveTheSlopeAndNoIntervalThreeGiveBoth) {
  const LinearTrend two = linearTrend({1.0, 2.0}, {3.0, 5.0});
  EXPECT_EQ(two.slope, 2.0);
  EXPECT_EQ(two.points, 2u);
  EXPECT_TRUE(std::isnan(two.std_error) && std::isnan(two.lower) && std::isnan(two.upper));
  // y = 1, 3, 2 over n = 1, 2, 3: slope 0.5 (R: coef(lm(c(1, 3, 2) ~ c(1, 2, 3)))[2]), residuals
  // -0.5, 1, -0.5: std error sqrt(1.5 / 1 / 2) = 0.866...
  const LinearTrend three = linearTrend({1.0, 2.0, 3.0}, {1.0, 3.0, 2.0});
  EXPECT_NEAR(three.slope, 0.5, 1e-15);
  EXPECT_NEAR(three.std_error, std::sqrt(0.75), 1e-15);
  EXPECT_LT(three.lower, three.slope);
  EXPECT_GT(three.upper, three.slope);
  EXPECT_TRUE(std::isnan(linearTrend({1.0}, {2.0}).slope));
  EXPECT_TRUE(std::isnan(linearTrend({2.0, 2.0}, {1.0, 3.0}).slope)) << "n all equal";
}

TEST(LearningCurve, RefusesTooFewPointsAndBadValues) {
  EXPECT_THROW((void)fitLearningCurve({1, 2, 3}, {3, 2, 1}, CurveLaw::kPower), InputError);
  EXPECT_THROW((void)fitLearningCurve({0, 1, 2, 3}, {3, 2, 1, 1}, CurveLaw::kPower), InputError);
  EXPECT_THROW((void)fitLearningCurve({1, 2, 3, 4}, {3, 2, NAN, 1}, CurveLaw::kPower), InputError);
  EXPECT_THROW((void)fitLearningCurve({2, 2, 2, 2}, {3, 2, 1, 1}, CurveLaw::kExponential), InputError);
}

}  // namespace
}  // namespace hattr::analysis
