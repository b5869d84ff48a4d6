// The studentized range distribution by the Copenhaver & Holland (1988) quadrature.
//
// P(Q <= q) = ∫_0^∞ f(u) W(q * sqrt(u / 2)) du, where u = 2 chi^2_df / df has density
// f(u) = df^(df/2) 2^(-df) / Γ(df/2) * u^(df/2 - 1) exp(-df u / 4), and W(w) is the CDF of
// the range of `groups` standard normals (Hartley's form):
//   W(w) = (2Φ(w/2) - 1)^groups + 2 groups ∫_{w/2}^∞ φ(x) (Φ(x) - Φ(x - w))^(groups-1) dx.
// The outer integral runs over intervals of length 2 * ulen with a 16-point Gauss–Legendre
// rule until an interval adds less than 1e-14; the inner one over 2 or 3 intervals of
// [w/2, 8] with a 12-point rule. Cut-offs skip terms below ~1e-13. The constants and the
// order of summation follow the published algorithm as used by R's ptukey(), so the two
// agree to rounding.

#include "hattr/analysis/studentized_range.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string_view>

#include <boost/math/distributions/students_t.hpp>
#include <boost/math/tools/toms748_solve.hpp>

#include "hattr/core/error.hpp"

namespace hattr::analysis {
namespace {

/// ln Γ(x) for x > 0, safe on any thread: std::lgamma writes the global signgam (a data race
/// when analyses run on several threads, as a power analysis's replicates do); lgamma_r is the
/// same glibc function without it, so the value is the same to the bit.
double logGamma(double x) {
  int sign = 0;
  return ::lgamma_r(x, &sign);
}

// Positive nodes and weights of the 12-point Gauss–Legendre rule (inner integral).
constexpr std::array<double, 6> kRangeNodes = {
    0.981560634246719250690549090149, 0.904117256370474856678465866119,
    0.769902674194304687036893833213, 0.587317954286617447296702418941,
    0.367831498998180193752691536644, 0.125233408511468915472441369464};
constexpr std::array<double, 6> kRangeWeights = {
    0.047175336386511827194615961485, 0.106939325995318430960254718194,
    0.160078328543346226334652529543, 0.203167426723065921749064455810,
    0.233492536538354808760849898925, 0.249147045813402785000562436043};

// Positive nodes and weights of the 16-point Gauss–Legendre rule (outer integral).
constexpr std::array<double, 8> kChiNodes = {
    0.989400934991649932596154173450, 0.944575023073232576077988415535,
    0.865631202387831743880467897712, 0.755404408355003033895101194847,
    0.617876244402643748446671764049, 0.458016777657227386342419442984,
    0.281603550779258913230460501460, 0.950125098376374401853193354250e-1};
constexpr std::array<double, 8> kChiWeights = {
    0.271524594117540948517805724560e-1, 0.622535239386478928628438369944e-1,
    0.951585116824927848099251076022e-1, 0.124628971255533872052476282192,
    0.149595988816576732081501730547, 0.169156519395002538189312079030,
    0.182603415044923588866763667969, 0.189450610455068496285396723208};

// Above this many degrees of freedom the chi factor is taken as 1 (infinite df).
constexpr double kLargeDf = 25000.0;

constexpr double kSqrtTwoPi = 2.506628274631000502415765284811;

double normalCdf(double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); }

// W(w): P(range of `groups` standard normals < w).
double rangeCdf(double w, double groups) {
  constexpr double kUpper = 8.0;           // the inner integral stops at x = 8
  constexpr double kLogSkipOuter = -50.0;  // (2Φ(w/2) - 1)^groups below e^-50 is 0
  constexpr double kLogSkipInner = -30.0;  // integrand factors below e^-30 are dropped
  constexpr double kMaxSquare = 60.0;      // exp(-x²/2) < 1e-13 beyond x² = 60
  const double half_w = 0.5 * w;
  if (half_w >= kUpper) return 1.0;

  // First term: (2Φ(w/2) - 1)^groups.
  double p = 2.0 * normalCdf(half_w) - 1.0;
  p = p >= std::exp(kLogSkipOuter / groups) ? std::pow(p, groups) : 0.0;

  // Second term over [w/2, 8], two intervals for large w, three otherwise.
  const int intervals = w > 3.0 ? 2 : 3;
  long double lower = half_w;
  const double step = (kUpper - half_w) / intervals;
  long double upper = lower + step;
  long double sum = 0.0L;
  const double power = groups - 1.0;
  for (int interval = 0; interval < intervals; ++interval) {
    long double interval_sum = 0.0L;
    const auto center = static_cast<double>(0.5L * (upper + lower));
    const auto half = static_cast<double>(0.5L * (upper - lower));
    // Nodes in increasing order: -x_0 ... -x_5, x_5 ... x_0.
    for (int node = 0; node < 12; ++node) {
      const int k = node < 6 ? node : 11 - node;
      const double x = center + half * (node < 6 ? -kRangeNodes[k] : kRangeNodes[k]);
      const double square = x * x;
      if (square > kMaxSquare) break;
      const double inside = normalCdf(x) - normalCdf(x - w);
      if (inside >= std::exp(kLogSkipInner / power)) {
        interval_sum += kRangeWeights[k] * std::exp(-0.5 * square) * std::pow(inside, power);
      }
    }
    interval_sum *= 2.0 * half * groups / kSqrtTwoPi;
    sum += interval_sum;
    lower = upper;
    upper += step;
  }
  p += static_cast<double>(sum);
  if (p <= std::exp(kLogSkipInner)) return 0.0;
  return std::min(p, 1.0);
}

void checkArguments(std::string_view function, double x, int groups, double df) {
  HATTR_THROW_UNLESS(!std::isnan(x), "{}: expected a number, got NaN", function);
  HATTR_THROW_UNLESS(groups >= 2, "{}: groups: expected at least 2, got {}", function, groups);
  HATTR_THROW_UNLESS(df >= 2.0, "{}: df: expected at least 2 (or +infinity), got {}", function, df);
}

double cdfUnchecked(double q, int groups, double df) {
  if (q <= 0.0) return 0.0;
  if (std::isinf(q)) return 1.0;
  const double c = groups;
  if (df > kLargeDf) return rangeCdf(q, c);

  // log of the chi density's constant, plus the log of the interval half-length.
  const double half_df = 0.5 * df;
  const double quarter_df = 0.25 * df;
  const double ulen = df <= 100.0 ? 1.0 : df <= 800.0 ? 0.5 : df <= 5000.0 ? 0.25 : 0.125;
  const double log_constant =
      half_df * std::log(df) - df * std::numbers::ln2 - logGamma(half_df) + std::log(ulen);
  const double power = half_df - 1.0;

  constexpr double kLogSkip = -30.0;    // density factors below e^-30 are dropped
  constexpr double kConverged = 1e-14;  // stop when an interval adds less than this
  double total = 0.0;
  for (int interval = 1; interval <= 50; ++interval) {
    double interval_sum = 0.0;
    const double center = (2 * interval - 1) * ulen;
    // Nodes: center - x_k ulen for k = 0..7, then center + x_k ulen for k = 0..7.
    for (int node = 0; node < 16; ++node) {
      const int k = node % 8;
      const double offset = kChiNodes[k] * ulen;
      const double u = node < 8 ? center - offset : center + offset;
      const double log_density =
          node < 8 ? log_constant + power * std::log(u) + (offset - center) * quarter_df
                   : log_constant + power * std::log(u) - (offset + center) * quarter_df;
      if (log_density >= kLogSkip) {
        interval_sum +=
            rangeCdf(q * std::sqrt(u * 0.5), c) * kChiWeights[k] * std::exp(log_density);
      }
    }
    // At least 1 / ulen intervals, so that a small left tail is not cut short.
    if (interval * ulen >= 1.0 && interval_sum <= kConverged) break;
    total += interval_sum;
  }
  return std::min(total, 1.0);
}

}  // namespace

double studentizedRangeCdf(double q, int groups, double df) {
  checkArguments("studentizedRangeCdf", q, groups, df);
  return cdfUnchecked(q, groups, df);
}

double studentizedRangeUpperTail(double q, int groups, double df) {
  checkArguments("studentizedRangeUpperTail", q, groups, df);
  return 0.5 - cdfUnchecked(q, groups, df) + 0.5;
}

double studentizedRangeQuantile(double p, int groups, double df) {
  checkArguments("studentizedRangeQuantile", p, groups, df);
  HATTR_THROW_UNLESS(p > 0.0 && p < 1.0,
                     "studentizedRangeQuantile: p: expected a probability in (0, 1), got {}", p);
  const auto excess = [&](double q) { return cdfUnchecked(q, groups, df) - p; };
  // Bracket the root: the CDF is 0 at 0 and rises to 1.
  double low = 0.0;
  double high = 1.0;
  while (excess(high) < 0.0) {
    low = high;
    high *= 2.0;
    HATTR_DEMAND(high < 1e6, "studentized range quantile of p = {} not bracketed", p);
  }
  if (excess(high) == 0.0) return high;
  std::uintmax_t max_iterations = 200;
  const auto [a, b] = boost::math::tools::toms748_solve(
      excess, low, high, boost::math::tools::eps_tolerance<double>(50), max_iterations);
  return 0.5 * (a + b);
}

double studentTQuantile(double p, double df) {
  HATTR_THROW_UNLESS(p > 0.0 && p < 1.0 && df > 0.0 && std::isfinite(df),
                     "studentTQuantile: expected 0 < p < 1 and df > 0, got p = {}, df = {}", p, df);
  return boost::math::quantile(boost::math::students_t_distribution<double>(df), p);
}

}  // namespace hattr::analysis
