#pragma once
/// Learning curves: a score over practice fitted by the two laws of practice the
/// motor-learning literature compares (Newell and Rosenbloom 1981; Heathcote, Brown and
/// Mewhort 2000, "The power law repealed: the case for an exponential law of practice"):
///
///   exponential  y(n) = a + b·exp(−c·(n − 1))
///   power        y(n) = a + b·n^(−c)
///
/// n is the trial number (from 1), a the asymptote (the score practice tends to), b the
/// amount there is to learn (y(1) − a), c the learning rate. Least squares, as R's nls():
/// a and b are linear given c, so c is found by a one-dimensional search of the residual
/// sum of squares (variable projection), then every parameter's standard error comes from
/// the Jacobian at the optimum and its confidence interval from Student's t with m − 3
/// degrees of freedom, as R's summary(nls()) and confint.default() with t quantiles.
///
/// Offline analysis code; no shared state.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace hattr::analysis {

enum class CurveLaw { kExponential, kPower };

/// One parameter with its standard error and confidence interval.
struct CurveParameter {
  double estimate = 0.0;
  double std_error = 0.0;
  double lower = 0.0;
  double upper = 0.0;
};

struct CurveFit {
  CurveLaw law = CurveLaw::kExponential;
  CurveParameter asymptote;  ///< a [score unit]
  CurveParameter amplitude;  ///< b [score unit]
  CurveParameter rate;       ///< c [per trial]
  double rss = 0.0;          ///< residual sum of squares
  double sigma = 0.0;        ///< residual standard error √(rss / (m − 3))
  std::size_t points = 0;
  double confidence = 0.95;
  /// "" when the fit is interior; else why its intervals should not be read (the rate on
  /// its search bound: no curvature, or learning finished within the first trials).
  std::string note;
  [[nodiscard]] double at(double n) const;  ///< the fitted score at trial n
};

/// Fits `law` to scores y at trials n (n ≥ 1, at least 4 points, not all n equal). Throws
/// InputError otherwise or on non-finite values.
[[nodiscard]] CurveFit fitLearningCurve(const std::vector<double>& n, const std::vector<double>& y, CurveLaw law,
                                        double confidence = 0.95);

/// A straight line's slope by least squares, with its standard error and t interval (m − 2
/// degrees of freedom): whether scores rose or fell over trials, whatever the curve's shape.
struct LinearTrend {
  double slope = 0.0;  ///< [score unit per trial]
  double std_error = 0.0;
  double lower = 0.0;
  double upper = 0.0;
  std::size_t points = 0;
};

/// The least-squares trend of y over n. The slope needs 2 points or more and n not all equal;
/// its standard error and interval need 3 or more (NaN otherwise); NaN throughout else.
[[nodiscard]] LinearTrend linearTrend(const std::vector<double>& n, const std::vector<double>& y,
                                      double confidence = 0.95);

[[nodiscard]] const char* curveLawName(CurveLaw law);  ///< "exponential", "power"
[[nodiscard]] nlohmann::json toJson(const CurveFit& fit);

}  // namespace hattr::analysis
