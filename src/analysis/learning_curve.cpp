// Learning curves fitted by the exponential and the power law of practice (learning_curve.hpp).

#include "hattr/analysis/learning_curve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>
#include <boost/math/distributions/students_t.hpp>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"

namespace hattr::analysis {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The rate's search range [per trial]: from hardly any learning over thousands of trials to
// learning done after the first.
constexpr double kRateMin = 1e-4;
constexpr double kRateMax = 20.0;

/// The law's shape at trial n for rate c: exp(−c(n − 1)) or n^(−c).
double shape(CurveLaw law, double n, double c) {
  return law == CurveLaw::kExponential ? std::exp(-c * (n - 1.0)) : std::exp(-c * std::log(n));
}

/// d shape / dc.
double shapeSlope(CurveLaw law, double n, double c) {
  return law == CurveLaw::kExponential ? -(n - 1.0) * shape(law, n, c) : -std::log(n) * shape(law, n, c);
}

/// For a fixed rate: the least-squares asymptote and amplitude, and the residual sum of squares.
struct Linear {
  double a = 0.0;
  double b = 0.0;
  double rss = std::numeric_limits<double>::infinity();
};

Linear linearFit(const std::vector<double>& n, const std::vector<double>& y, CurveLaw law, double c) {
  const std::size_t m = n.size();
  double se = 0.0, see = 0.0, sy = 0.0, sey = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    const double e = shape(law, n[i], c);
    se += e;
    see += e * e;
    sy += y[i];
    sey += e * y[i];
  }
  const auto count = static_cast<double>(m);
  const double det = count * see - se * se;
  Linear out;
  if (!(std::abs(det) > 1e-300)) return out;
  out.b = (count * sey - se * sy) / det;
  out.a = (sy - out.b * se) / count;
  out.rss = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    const double r = y[i] - out.a - out.b * shape(law, n[i], c);
    out.rss += r * r;
  }
  return out;
}

/// The rate minimizing the residual sum of squares: a grid in log c, then golden-section
/// search between the best point's neighbours.
double bestRate(const std::vector<double>& n, const std::vector<double>& y, CurveLaw law, bool& on_bound) {
  constexpr int kGrid = 240;
  const double lo = std::log(kRateMin);
  const double hi = std::log(kRateMax);
  const auto rss = [&](double log_c) { return linearFit(n, y, law, std::exp(log_c)).rss; };
  int best = 0;
  double best_rss = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kGrid; ++i) {
    const double r = rss(lo + (hi - lo) * i / kGrid);
    if (r < best_rss) {
      best_rss = r;
      best = i;
    }
  }
  on_bound = best == 0 || best == kGrid;
  double a = lo + (hi - lo) * std::max(best - 1, 0) / kGrid;
  double b = lo + (hi - lo) * std::min(best + 1, kGrid) / kGrid;
  const double golden = (std::sqrt(5.0) - 1.0) / 2.0;
  double x1 = b - golden * (b - a);
  double x2 = a + golden * (b - a);
  double f1 = rss(x1);
  double f2 = rss(x2);
  while (b - a > 1e-12) {
    if (f1 < f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - golden * (b - a);
      f1 = rss(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + golden * (b - a);
      f2 = rss(x2);
    }
  }
  return std::exp((a + b) / 2.0);
}

}  // namespace

double CurveFit::at(double n) const { return asymptote.estimate + amplitude.estimate * shape(law, n, rate.estimate); }

LinearTrend linearTrend(const std::vector<double>& n, const std::vector<double>& y, double confidence) {
  LinearTrend out{kNaN, kNaN, kNaN, kNaN, n.size()};
  if (n.size() != y.size() || n.size() < 2) return out;
  const auto m = static_cast<double>(n.size());
  double mn = 0.0, my = 0.0;
  for (std::size_t i = 0; i < n.size(); ++i) {
    mn += n[i] / m;
    my += y[i] / m;
  }
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t i = 0; i < n.size(); ++i) {
    sxx += (n[i] - mn) * (n[i] - mn);
    sxy += (n[i] - mn) * (y[i] - my);
  }
  if (!(sxx > 0.0)) return out;
  out.slope = sxy / sxx;
  if (n.size() < 3) return out;  // a line through two points: no residual to judge it by
  double rss = 0.0;
  for (std::size_t i = 0; i < n.size(); ++i) {
    const double r = y[i] - my - out.slope * (n[i] - mn);
    rss += r * r;
  }
  out.std_error = std::sqrt(rss / (m - 2.0) / sxx);
  const double t = boost::math::quantile(boost::math::students_t(m - 2.0), 0.5 + confidence / 2.0);
  out.lower = out.slope - t * out.std_error;
  out.upper = out.slope + t * out.std_error;
  return out;
}

const char* curveLawName(CurveLaw law) { return law == CurveLaw::kExponential ? "exponential" : "power"; }

CurveFit fitLearningCurve(const std::vector<double>& n, const std::vector<double>& y, CurveLaw law, double confidence) {
  HATTR_THROW_UNLESS(n.size() == y.size(), "learning curve: {} trial numbers for {} scores", n.size(), y.size());
  HATTR_THROW_UNLESS(n.size() >= 4, "learning curve: {} points; a three-parameter curve needs at least 4", n.size());
  HATTR_THROW_UNLESS(confidence > 0.0 && confidence < 1.0, "learning curve: confidence {}; expected between 0 and 1",
                     confidence);
  for (std::size_t i = 0; i < n.size(); ++i) {
    HATTR_THROW_UNLESS(std::isfinite(n[i]) && n[i] >= 1.0, "learning curve: trial number {} at point {}; expected 1 or more",
                       n[i], i + 1);
    HATTR_THROW_UNLESS(std::isfinite(y[i]), "learning curve: score {} at point {}; expected a finite number", y[i], i + 1);
  }
  HATTR_THROW_UNLESS(*std::max_element(n.begin(), n.end()) > *std::min_element(n.begin(), n.end()),
                     "learning curve: every point is at trial {}; a curve needs several trials", n[0]);

  CurveFit fit;
  fit.law = law;
  fit.points = n.size();
  fit.confidence = confidence;
  bool on_bound = false;
  const double c = bestRate(n, y, law, on_bound);
  const Linear linear = linearFit(n, y, law, c);
  fit.asymptote.estimate = linear.a;
  fit.amplitude.estimate = linear.b;
  fit.rate.estimate = c;
  fit.rss = linear.rss;
  const auto df = static_cast<double>(n.size()) - 3.0;
  fit.sigma = df > 0.0 ? std::sqrt(linear.rss / df) : kNaN;
  if (!(linear.rss > 0.0)) {
    fit.note = "the scores lie exactly on the curve: no residual to estimate intervals from";
  } else if (on_bound) {
    fit.note = fmt::format("the rate is on its search bound ({} per trial): {}", c,
                           c < 1.0 ? "the scores show no curvature to fit" : "the change is all in the first trials");
  }

  // Standard errors from the Jacobian at the optimum: cov = σ² (JᵀJ)⁻¹.
  Eigen::MatrixXd j(static_cast<Eigen::Index>(n.size()), 3);
  for (std::size_t i = 0; i < n.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    j(row, 0) = 1.0;
    j(row, 1) = shape(law, n[i], c);
    j(row, 2) = linear.b * shapeSlope(law, n[i], c);
  }
  const Eigen::Matrix3d jtj = j.transpose() * j;
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(jtj);
  const double t = df > 0.0 ? boost::math::quantile(boost::math::students_t(df), 0.5 + confidence / 2.0) : kNaN;
  const bool estimable = lu.isInvertible() && df > 0.0 && linear.rss > 0.0;
  const Eigen::Matrix3d cov = estimable ? Eigen::Matrix3d(fit.sigma * fit.sigma * lu.inverse()) : Eigen::Matrix3d::Constant(kNaN);
  CurveParameter* parameters[] = {&fit.asymptote, &fit.amplitude, &fit.rate};
  for (int k = 0; k < 3; ++k) {
    CurveParameter& p = *parameters[k];
    p.std_error = cov(k, k) >= 0.0 ? std::sqrt(cov(k, k)) : kNaN;
    p.lower = p.estimate - t * p.std_error;
    p.upper = p.estimate + t * p.std_error;
  }
  return fit;
}

nlohmann::json toJson(const CurveFit& fit) {
  const auto parameter = [&](const CurveParameter& p) {
    return nlohmann::json{{"estimate", jsonNumber(p.estimate)}, {"std_error", jsonNumber(p.std_error)},
                          {"lower", jsonNumber(p.lower)}, {"upper", jsonNumber(p.upper)}};
  };
  return {{"law", curveLawName(fit.law)},        {"asymptote", parameter(fit.asymptote)},
          {"amplitude", parameter(fit.amplitude)}, {"rate", parameter(fit.rate)},
          {"rss", jsonNumber(fit.rss)},                {"sigma", jsonNumber(fit.sigma)},
          {"points", fit.points},                  {"confidence", fit.confidence},
          {"note", fit.note}};
}

}  // namespace hattr::analysis
