// Inference for linear mixed models as lmerTest makes it (Kuznetsova, Brockhoff and
// Christensen 2017, "lmerTest package: tests in linear mixed effects models"):
// Satterthwaite's degrees of freedom from the Hessian of the deviance in the variance
// parameters (θ, σ) and the Jacobian of cov(β̂) in them, and type III hypotheses.

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "lmm_model.hpp"

namespace hattr::analysis::lmm {
namespace {

constexpr int kRichardsonLevels = 4;

/// The step of a numerical derivative at x, as numDeriv takes it: a fraction of |x| (0.1 for
/// its hessian, 1e-4 for its jacobian), or 1e-4 at (near) zero.
double stepAt(double x, double fraction) {
  constexpr double kZero = 1.7817416127494958e-05;  // numDeriv's zero.tol: √(ε / 7e-7)
  return std::abs(x) < kZero ? 1e-4 : fraction * std::abs(x);
}

/// Richardson extrapolation of estimates made with steps h, h/2, h/4, ... whose error is
/// a series in h²; returns the extrapolated value.
template <class T>
T extrapolate(std::vector<T> d) {
  for (int m = 1; m < static_cast<int>(d.size()); ++m) {
    const double four_m = std::pow(4.0, m);
    for (std::size_t k = 0; k + static_cast<std::size_t>(m) < d.size(); ++k) {
      d[k] = (four_m * d[k + 1] - d[k]) / (four_m - 1.0);
    }
  }
  return d[0];
}

/// The Hessian of f at x by central differences, Richardson-extrapolated.
template <class F>
Eigen::MatrixXd hessian(F&& f, const Eigen::VectorXd& x) {
  const auto k = x.size();
  const double f0 = f(x);
  Eigen::MatrixXd h(k, k);
  for (Eigen::Index i = 0; i < k; ++i) {
    for (Eigen::Index j = 0; j <= i; ++j) {
      std::vector<double> d;
      double hi = stepAt(x[i], 0.1);
      double hj = stepAt(x[j], 0.1);
      for (int level = 0; level < kRichardsonLevels; ++level, hi /= 2.0, hj /= 2.0) {
        const auto at = [&](double si, double sj) {
          Eigen::VectorXd p = x;
          p[i] += si;
          p[j] += sj;
          return f(p);
        };
        if (i == j) {
          d.push_back((at(hi / 2.0, hi / 2.0) - 2.0 * f0 + at(-hi / 2.0, -hi / 2.0)) / (hi * hi));
        } else {
          d.push_back((at(hi, hj) - at(hi, -hj) - at(-hi, hj) + at(-hi, -hj)) / (4.0 * hi * hj));
        }
      }
      h(i, j) = h(j, i) = extrapolate(d);
    }
  }
  return h;
}

/// The derivative of a matrix-valued g in each element of x, Richardson-extrapolated.
template <class G>
std::vector<Eigen::MatrixXd> jacobian(G&& g, const Eigen::VectorXd& x) {
  std::vector<Eigen::MatrixXd> out;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    std::vector<Eigen::MatrixXd> d;
    double h = stepAt(x[i], 1e-4);  // numDeriv's jacobian: d = 1e-4
    for (int level = 0; level < kRichardsonLevels; ++level, h /= 2.0) {
      Eigen::VectorXd plus = x;
      Eigen::VectorXd minus = x;
      plus[i] += h;
      minus[i] -= h;
      d.push_back((g(plus) - g(minus)) / (2.0 * h));
    }
    out.push_back(extrapolate(d));
  }
  return out;
}

double quadraticForm(const Eigen::RowVectorXd& l, const Eigen::MatrixXd& m) { return l * m * l.transpose(); }

/// lmerTest's get_Fstat_ddf: the denominator degrees of freedom of an F from the
/// Satterthwaite degrees of freedom of its q orthogonal contrasts.
double fDenominatorDf(const std::vector<double>& nu) {
  if (nu.size() == 1) return nu[0];
  bool equal = true;
  for (std::size_t i = 1; i < nu.size(); ++i) equal = equal && std::abs(nu[i] - nu[i - 1]) < 1e-8;
  if (equal) {
    double sum = 0.0;
    for (double v : nu) sum += v;
    return sum / static_cast<double>(nu.size());
  }
  double e = 0.0;
  for (double v : nu) {
    if (v <= 2.0) return 2.0;
    e += v / (v - 2.0);
  }
  return 2.0 * e / (e - static_cast<double>(nu.size()));
}

/// R's zapsmall(x, digits = 7): rounds every element to 7 significant digits of the largest.
void zapSmall(Eigen::MatrixXd& m) {
  const double largest = m.cwiseAbs().maxCoeff();
  if (!(largest > 0.0)) return;
  const int digits = std::max(0, 7 - static_cast<int>(std::ceil(std::log10(largest))));
  const double scale = std::pow(10.0, digits);
  m = m.unaryExpr([scale](double v) { return std::round(v * scale) / scale; });
}

/// The columns of X that code term t.
std::vector<Eigen::Index> columnsOf(const Design& x, int term) {
  std::vector<Eigen::Index> out;
  for (std::size_t c = 0; c < x.term_of_column.size(); ++c) {
    if (x.term_of_column[c] == term) out.push_back(static_cast<Eigen::Index>(c));
  }
  return out;
}

Eigen::MatrixXd selectColumns(const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& columns) {
  Eigen::MatrixXd out(m.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) out.col(static_cast<Eigen::Index>(c)) = m.col(columns[c]);
  return out;
}

/// lmerTest's term_contain: term a is contained in term b when b has all of a's variables
/// and more, and the same numeric ones, counting in each term only the variables R's terms()
/// codes 1 (by contrasts: see termCodes()).
bool contains(const Model& m, const std::vector<std::vector<int>>& codes, std::size_t a, std::size_t b) {
  const auto coded = [&](std::size_t t, bool numeric_only) {
    Term out;
    const Term& term = m.formula.fixed[t];
    for (std::size_t k = 0; k < term.size(); ++k) {
      const bool numeric = !m.variables[static_cast<std::size_t>(term[k])].factor;
      if (codes[t][k] == 1 && (numeric || !numeric_only)) out.push_back(term[k]);
    }
    return out;
  };
  const Term va = coded(a, false);
  const Term vb = coded(b, false);
  return std::includes(vb.begin(), vb.end(), va.begin(), va.end()) && vb.size() > va.size() &&
         coded(a, true) == coded(b, true);
}

/// lmerTest's doolittle(): the unit lower triangular factor of X'X, small values zeroed.
Eigen::MatrixXd doolittleLower(const Eigen::MatrixXd& x) {
  constexpr double kEps = 1e-6;
  const auto n = x.rows();
  Eigen::MatrixXd l = Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      u(i, j) = x(i, j);
      for (Eigen::Index k = 0; k < i; ++k) u(i, j) -= l(i, k) * u(k, j);
    }
    for (Eigen::Index j = i + 1; j < n; ++j) {
      l(j, i) = x(j, i);
      for (Eigen::Index k = 0; k < i; ++k) l(j, i) -= l(j, k) * u(k, i);
      l(j, i) = std::abs(u(i, i)) < kEps ? 0.0 : l(j, i) / u(i, i);
    }
  }
  return l.unaryExpr([](double v) { return std::abs(v) < kEps ? 0.0 : v; });
}

/// lmerTest's type I hypotheses (get_contrasts_type1), used for a model of one term.
std::vector<Eigen::MatrixXd> typeOneHypotheses(const Model& m) {
  const Eigen::MatrixXd& x = m.fixed.matrix;
  const Eigen::MatrixXd l = doolittleLower(x.transpose() * x).transpose();
  std::vector<Eigen::MatrixXd> out;
  for (std::size_t t = 0; t < m.formula.fixed.size(); ++t) {
    const std::vector<Eigen::Index> rows = columnsOf(m.fixed, static_cast<int>(t));
    Eigen::MatrixXd h(static_cast<Eigen::Index>(rows.size()), l.cols());
    for (std::size_t r = 0; r < rows.size(); ++r) h.row(static_cast<Eigen::Index>(r)) = l.row(rows[r]);
    out.push_back(h);
  }
  return out;
}

}  // namespace

Satterthwaite satterthwaite(Deviance& deviance, const Eigen::VectorXd& theta, double sigma) {
  Satterthwaite s;
  const auto k = theta.size();
  Eigen::VectorXd varpar(k + 1);
  varpar << theta, sigma;
  const auto split = [k](const Eigen::VectorXd& v) { return std::pair<Eigen::VectorXd, double>(v.head(k), v[k]); };
  s.vcov_beta = deviance.covarianceOfBeta(theta, sigma);

  // The asymptotic covariance of (θ, σ): twice the inverse Hessian of the deviance, over its
  // positive eigenvalues (lmerTest's as_lmerModLT).
  const Eigen::MatrixXd h = hessian(
      [&](const Eigen::VectorXd& v) {
        const auto [t, sd] = split(v);
        return deviance.atSigma(t, sd);
      },
      varpar);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(h);
  constexpr double kTolerance = 1e-8;
  Eigen::MatrixXd inverse = Eigen::MatrixXd::Zero(k + 1, k + 1);
  int negative = 0;
  int zero = 0;
  for (Eigen::Index i = 0; i <= k; ++i) {
    const double value = eigen.eigenvalues()[i];
    negative += value < -kTolerance ? 1 : 0;
    zero += std::abs(value) <= kTolerance ? 1 : 0;
    if (value > kTolerance) inverse += eigen.eigenvectors().col(i) * eigen.eigenvectors().col(i).transpose() / value;
  }
  if (negative > 0) {
    s.warnings.push_back(fmt::format("the model may not have converged: the Hessian of the deviance in the variance "
                                     "parameters has {} negative eigenvalue(s)", negative));
  }
  if (zero > 0) {
    s.warnings.push_back(fmt::format("the Hessian of the deviance in the variance parameters has {} eigenvalue(s) near "
                                     "zero (a variance on its boundary?): degrees of freedom use the others", zero));
  }
  s.vcov_varpar = 2.0 * inverse;
  s.jacobian = jacobian(
      [&](const Eigen::VectorXd& v) {
        const auto [t, sd] = split(v);
        return deviance.covarianceOfBeta(t, sd);
      },
      varpar);
  deviance(theta);  // leave the solution at the optimum
  return s;
}

void testContrast(const Satterthwaite& s, const Eigen::VectorXd& beta, const Eigen::RowVectorXd& l, LmmCoefficient& out) {
  const double variance = quadraticForm(l, s.vcov_beta);
  Eigen::RowVectorXd gradient(static_cast<Eigen::Index>(s.jacobian.size()));
  for (std::size_t i = 0; i < s.jacobian.size(); ++i) gradient[static_cast<Eigen::Index>(i)] = quadraticForm(l, s.jacobian[i]);
  const double denominator = quadraticForm(gradient, s.vcov_varpar);
  out.estimate = l * beta;
  out.std_error = std::sqrt(variance);
  out.df = 2.0 * variance * variance / denominator;
  out.t = out.estimate / out.std_error;
  out.p = out.lower = out.upper = std::numeric_limits<double>::quiet_NaN();
  if (std::isfinite(out.df) && out.df > 0.0 && std::isfinite(out.t)) {
    const boost::math::students_t t(out.df);
    out.p = 2.0 * boost::math::cdf(boost::math::complement(t, std::abs(out.t)));
    const double half = boost::math::quantile(t, 0.975) * out.std_error;
    out.lower = out.estimate - half;
    out.upper = out.estimate + half;
  }
}

LmmTermTest testHypothesis(const Satterthwaite& s, const Eigen::VectorXd& beta, const Eigen::MatrixXd& l) {
  LmmTermTest test;
  const auto fTest = [&](double f, double q, double ddf) {
    test.f = f;
    test.num_df = q;
    test.den_df = ddf;
    test.p = std::numeric_limits<double>::quiet_NaN();
    if (std::isfinite(ddf) && ddf > 0.0 && std::isfinite(f)) {
      test.p = boost::math::cdf(boost::math::complement(boost::math::fisher_f(q, ddf), f));
    }
  };
  LmmCoefficient one;
  if (l.rows() == 1) {
    testContrast(s, beta, l.row(0), one);
    fTest(one.t * one.t, 1.0, one.df);
    return test;
  }
  // Rotate the hypothesis to orthogonal contrasts: the eigenvectors of L cov(β̂) Lᵀ, largest first.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(l * s.vcov_beta * l.transpose());
  const auto rows = l.rows();
  const double largest = eigen.eigenvalues()[rows - 1];
  const double tolerance = std::max(std::sqrt(std::numeric_limits<double>::epsilon()) * largest, 0.0);
  std::vector<Eigen::Index> positive;
  for (Eigen::Index i = rows; i-- > 0;) {
    if (eigen.eigenvalues()[i] > tolerance) positive.push_back(i);
  }
  const auto q = static_cast<double>(positive.size());
  if (positive.empty()) {
    fTest(std::numeric_limits<double>::quiet_NaN(), 0.0, std::numeric_limits<double>::quiet_NaN());
    return test;
  }
  if (positive.size() == 1) {
    testContrast(s, beta, eigen.eigenvectors().col(positive[0]).transpose() * l, one);
    fTest(one.t * one.t, 1.0, one.df);
    return test;
  }
  double sum_t2 = 0.0;
  std::vector<double> nu;
  for (Eigen::Index i : positive) {
    const Eigen::RowVectorXd contrast = eigen.eigenvectors().col(i).transpose() * l;
    const double d = eigen.eigenvalues()[i];
    const double estimate = contrast * beta;
    sum_t2 += estimate * estimate / d;
    Eigen::RowVectorXd gradient(static_cast<Eigen::Index>(s.jacobian.size()));
    for (std::size_t j = 0; j < s.jacobian.size(); ++j) gradient[static_cast<Eigen::Index>(j)] = quadraticForm(contrast, s.jacobian[j]);
    nu.push_back(2.0 * d * d / quadraticForm(gradient, s.vcov_varpar));
  }
  fTest(sum_t2 / q, q, fDenominatorDf(nu));
  return test;
}

std::vector<Eigen::MatrixXd> typeThreeHypotheses(const Model& m) {
  const Design& x = m.fixed;
  const auto p = x.matrix.cols();
  const std::size_t terms = m.formula.fixed.size();
  if (p <= 1 || terms <= 1) return typeOneHypotheses(m);

  // L = (X⁺ X̃)ᵀ, X̃ coding every factor by indicators: each of X̃'s columns in X's terms.
  const Design full = designMatrix(m.variables, m.formula.intercept, m.formula.fixed, true);
  Eigen::MatrixXd l = x.matrix.colPivHouseholderQr().solve(full.matrix).transpose();
  zapSmall(l);
  // Orthogonalize each term's columns to those of the terms that contain it, highest first.
  const std::vector<std::vector<int>> codes = termCodes(m.formula.fixed);
  std::vector<std::size_t> order(terms);
  for (std::size_t t = 0; t < terms; ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return m.formula.fixed[a].size() > m.formula.fixed[b].size(); });
  for (std::size_t t : order) {
    std::vector<Eigen::Index> containing;
    for (std::size_t other = 0; other < terms; ++other) {
      if (!contains(m, codes, t, other)) continue;
      const std::vector<Eigen::Index> c = columnsOf(x, static_cast<int>(other));
      containing.insert(containing.end(), c.begin(), c.end());
    }
    const std::vector<Eigen::Index> own = columnsOf(x, static_cast<int>(t));
    if (containing.empty() || own.empty()) continue;
    const Eigen::MatrixXd basis = selectColumns(l, containing);
    const Eigen::MatrixXd target = selectColumns(l, own);
    Eigen::MatrixXd residual = target - basis * basis.colPivHouseholderQr().solve(target);
    zapSmall(residual);
    for (std::size_t c = 0; c < own.size(); ++c) l.col(own[c]) = residual.col(static_cast<Eigen::Index>(c));
  }
  // Keep the rows of X's own columns; each term's hypothesis is its columns, transposed.
  Eigen::MatrixXd square(p, p);
  for (Eigen::Index c = 0; c < p; ++c) {
    const auto it = std::find(full.names.begin(), full.names.end(), x.names[static_cast<std::size_t>(c)]);
    HATTR_DEMAND(it != full.names.end(), "column {} of X is not a column of the indicator-coded matrix",
                 x.names[static_cast<std::size_t>(c)]);
    square.row(c) = l.row(it - full.names.begin());
  }
  std::vector<Eigen::MatrixXd> out;
  for (std::size_t t = 0; t < terms; ++t) {
    const Eigen::MatrixXd h = selectColumns(square, columnsOf(x, static_cast<int>(t))).transpose();
    std::vector<Eigen::Index> kept;
    for (Eigen::Index r = 0; r < h.rows(); ++r) {
      if (h.row(r).cwiseAbs().sum() > 1e-8) kept.push_back(r);
    }
    Eigen::MatrixXd reduced(static_cast<Eigen::Index>(kept.size()), p);
    for (std::size_t r = 0; r < kept.size(); ++r) reduced.row(static_cast<Eigen::Index>(r)) = h.row(kept[r]);
    out.push_back(reduced);
  }
  return out;
}

}  // namespace hattr::analysis::lmm
