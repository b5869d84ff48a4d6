// Linear mixed models: the profiled deviance, its minimization and the fit (lmm.hpp).

#include "hattr/analysis/lmm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <boost/math/distributions/chi_squared.hpp>
#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "lmm_model.hpp"

namespace hattr::analysis {
namespace lmm {

// ---- The profiled deviance (Bates et al. 2015, "Fitting linear mixed-effects models
// using lme4", section 3) -------------------------------------------------------------

Deviance::Deviance(const Model& model, bool reml, Eigen::Index dense_schur_limit) : model_(model), reml_(reml) {
  const Eigen::Index kDenseSchurLimit = dense_schur_limit;
  const auto n = model.y.size();
  const Eigen::MatrixXd& x = model.fixed.matrix;
  // Zᵀ and Λ's pattern: block b's level j owns columns offset_b + j·r_b ... + r_b − 1.
  std::vector<Eigen::Triplet<double>> z;
  std::vector<Eigen::Triplet<double>> lambda;
  Eigen::Index column = 0;
  for (const RandomBlock& b : model.blocks) {
    const auto r = static_cast<Eigen::Index>(b.size());
    for (Eigen::Index row = 0; row < n; ++row) {
      const Eigen::Index first = column + b.group_of_row[static_cast<std::size_t>(row)] * r;
      for (Eigen::Index k = 0; k < r; ++k) z.emplace_back(first + k, row, b.effects_matrix(row, k));
    }
    for (std::size_t level = 0; level < b.levels; ++level) {
      int theta = static_cast<int>(b.theta_offset);
      for (Eigen::Index c = 0; c < r; ++c) {
        for (Eigen::Index rr = c; rr < r; ++rr) {
          lambda.emplace_back(column + static_cast<Eigen::Index>(level) * r + rr,
                              column + static_cast<Eigen::Index>(level) * r + c, static_cast<double>(theta++));
        }
      }
    }
    column += static_cast<Eigen::Index>(b.levels) * r;
  }
  zt_.resize(column, n);
  zt_.setFromTriplets(z.begin(), z.end());
  z_ = zt_.transpose();
  ztz_ = (zt_ * zt_.transpose()).pruned();
  ztx_ = zt_ * x;
  zty_ = zt_ * model.y;
  xtx_ = x.transpose() * x;
  xty_ = x.transpose() * model.y;
  // Λ's values hold θ's indices until setLambda() maps them.
  lambda_.resize(column, column);
  lambda_.setFromTriplets(lambda.begin(), lambda.end());
  lambda_.makeCompressed();
  lambda_index_.resize(static_cast<std::size_t>(lambda_.nonZeros()));
  for (Eigen::Index i = 0; i < lambda_.nonZeros(); ++i) lambda_index_[static_cast<std::size_t>(i)] = static_cast<int>(lambda_.valuePtr()[i]);

  // A's pattern: ΛᵀZᵀZΛ's for Λ's pattern, with the whole diagonal, lower triangle.
  Eigen::SparseMatrix<double> ones = lambda_;
  for (Eigen::Index i = 0; i < ones.nonZeros(); ++i) ones.valuePtr()[i] = 1.0;
  a_ = lowerWithDiagonal(ones.transpose() * ztz_ * ones);
  first_block_size_ = static_cast<Eigen::Index>(model.blocks.front().size());
  first_block_columns_ = first_block_size_ * static_cast<Eigen::Index>(model.blocks.front().levels);
  const Eigen::Index rest = column - first_block_columns_;
  block_path_ = kDenseSchurLimit > 0 && rest <= kDenseSchurLimit &&
                rest * first_block_columns_ <= kDenseSchurLimit * kDenseSchurLimit;
  if (!block_path_) cholesky_.analyzePattern(a_);
  // A diagonal Λ (random intercepts, independent effects) scales each value of ZᵀZ by two
  // elements of θ: no sparse product per evaluation.
  diagonal_lambda_ = lambda_.nonZeros() == lambda_.rows();
  if (diagonal_lambda_) {
    ztz_lower_ = lowerWithDiagonal(ztz_);  // ZᵀZ + I: take the I off again
    for (Eigen::Index col = 0; col < ztz_lower_.outerSize(); ++col) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(ztz_lower_, col); it; ++it) {
        if (it.row() == col) it.valueRef() -= 1.0;
        a_theta_.emplace_back(lambda_index_[static_cast<std::size_t>(it.row())], lambda_index_[static_cast<std::size_t>(col)]);
      }
    }
    HATTR_DEMAND(ztz_lower_.nonZeros() == a_.nonZeros(), "the patterns of ZᵀZ and A differ");
  }
}

/// The lower triangle of a symmetric m + I, every diagonal element stored.
Eigen::SparseMatrix<double> Deviance::lowerWithDiagonal(const Eigen::SparseMatrix<double>& m) {
  Eigen::SparseMatrix<double> identity(m.rows(), m.cols());
  identity.setIdentity();
  Eigen::SparseMatrix<double> out = Eigen::SparseMatrix<double>(m.triangularView<Eigen::Lower>()) + identity;
  out.makeCompressed();
  return out;
}

void Deviance::setLambda(const Eigen::VectorXd& theta) {
  for (std::size_t i = 0; i < lambda_index_.size(); ++i) lambda_.valuePtr()[i] = theta[lambda_index_[i]];
}

// The penalized least squares at θ: A = ΛᵀZᵀZΛ + I, S = XᵀX − XᵀZΛ A⁻¹ ΛᵀZᵀX,
// β = S⁻¹(Xᵀy − XᵀZΛ A⁻¹ ΛᵀZᵀy), u = A⁻¹(ΛᵀZᵀy − ΛᵀZᵀXβ), and the penalized residual
// sum of squares ‖y − Xβ − ZΛu‖² + ‖u‖², computed from the residuals themselves.
void Deviance::solve(const Eigen::VectorXd& theta) {
  ++evaluations_;
  setLambda(theta);
  const Eigen::SparseMatrix<double> lambda_t = lambda_.transpose();
  if (diagonal_lambda_) {
    const double* base = ztz_lower_.valuePtr();
    double* value = a_.valuePtr();
    const int* row = a_.innerIndexPtr();
    for (Eigen::Index col = 0; col < a_.outerSize(); ++col) {
      for (Eigen::Index k = a_.outerIndexPtr()[col]; k < a_.outerIndexPtr()[col + 1]; ++k) {
        const auto& [i, j] = a_theta_[static_cast<std::size_t>(k)];
        value[k] = theta[i] * base[k] * theta[j] + (row[k] == col ? 1.0 : 0.0);
      }
    }
  } else {
    a_ = lowerWithDiagonal(lambda_t * ztz_ * lambda_);
  }
  factorA();
  const Eigen::MatrixXd b = lambda_t * ztx_;
  const Eigen::VectorXd bu = lambda_t * zty_;
  const Eigen::MatrixXd a_inv_b = solveA(b);
  const Eigen::VectorXd a_inv_bu = solveA(bu);
  schur_ = xtx_ - b.transpose() * a_inv_b;
  const Eigen::LLT<Eigen::MatrixXd> rx(schur_);
  HATTR_DEMAND(rx.info() == Eigen::Success, "the fixed-effects system is not positive definite");
  beta_ = rx.solve(xty_ - b.transpose() * a_inv_bu);
  const Eigen::VectorXd u = a_inv_bu - a_inv_b * beta_;
  const Eigen::VectorXd residual = model_.y - model_.fixed.matrix * beta_ - z_ * (lambda_ * u);
  pwrss_ = residual.squaredNorm() + u.squaredNorm();
  log_det_rx_ = 2.0 * rx.matrixLLT().diagonal().array().log().sum();
}

// A's factorization. The first block's part of A is block diagonal (each observation is in
// one level of the grouping factor), so while the rest of A is small its Schur complement
// is dense: S₂ = A₂₂ − C A₁₁⁻¹ Cᵀ with C = A₂₁, factored densely. Otherwise a sparse LDLᵀ.
void Deviance::factorA() {
  if (!block_path_) {
    cholesky_.factorize(a_);
    HATTR_DEMAND(cholesky_.info() == Eigen::Success, "the random-effects system is not positive definite");
    log_det_l_ = cholesky_.vectorD().array().log().sum();
    return;
  }
  const Eigen::Index r = first_block_size_;
  const Eigen::Index q1 = first_block_columns_;
  const Eigen::Index q2 = a_.rows() - q1;
  Eigen::MatrixXd diagonal = Eigen::MatrixXd::Zero(r, q1);  // A₁₁'s blocks side by side
  c_.setZero(q2, q1);
  Eigen::MatrixXd a22 = Eigen::MatrixXd::Zero(q2, q2);
  for (Eigen::Index col = 0; col < a_.outerSize(); ++col) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(a_, col); it; ++it) {
      if (col >= q1) {
        a22(it.row() - q1, col - q1) = it.value();
      } else if (it.row() >= q1) {
        c_(it.row() - q1, col) = it.value();
      } else {
        diagonal(it.row() % r, col) = it.value();
      }
    }
  }
  // Each level's block: its lower Cholesky factor, in place.
  log_det_l_ = 0.0;
  for (Eigen::Index j = 0; j < q1; j += r) {
    Eigen::Ref<Eigen::MatrixXd> block = diagonal.block(0, j, r, r);
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(block);
    HATTR_DEMAND(llt.info() == Eigen::Success, "a random-effects block is not positive definite");
    log_det_l_ += 2.0 * block.diagonal().array().log().sum();
  }
  block_factors_ = std::move(diagonal);
  if (q2 == 0) return;
  w_ = solveFirstBlock(c_.transpose());
  Eigen::MatrixXd s2 = a22.selfadjointView<Eigen::Lower>();
  s2.noalias() -= c_ * w_;
  schur_a_.compute(s2);
  HATTR_DEMAND(schur_a_.info() == Eigen::Success, "the random-effects system is not positive definite");
  log_det_l_ += 2.0 * schur_a_.matrixLLT().diagonal().array().log().sum();
}

// A₁₁⁻¹ b, level by level: forward and back substitution with each small factor L (r × r).
Eigen::MatrixXd Deviance::solveFirstBlock(const Eigen::MatrixXd& b) const {
  const Eigen::Index r = first_block_size_;
  Eigen::MatrixXd x = b;
  for (Eigen::Index j = 0; j < first_block_columns_; j += r) {
    const auto l = block_factors_.block(0, j, r, r);
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      for (Eigen::Index i = 0; i < r; ++i) {  // L v = x
        double v = x(j + i, c);
        for (Eigen::Index k = 0; k < i; ++k) v -= l(i, k) * x(j + k, c);
        x(j + i, c) = v / l(i, i);
      }
      for (Eigen::Index i = r; i-- > 0;) {  // Lᵀ w = v
        double w = x(j + i, c);
        for (Eigen::Index k = i + 1; k < r; ++k) w -= l(k, i) * x(j + k, c);
        x(j + i, c) = w / l(i, i);
      }
    }
  }
  return x;
}

Eigen::MatrixXd Deviance::solveA(const Eigen::MatrixXd& b) const {
  if (!block_path_) return cholesky_.solve(b);
  const Eigen::Index q1 = first_block_columns_;
  const Eigen::Index q2 = b.rows() - q1;
  Eigen::MatrixXd x(b.rows(), b.cols());
  const Eigen::MatrixXd y1 = solveFirstBlock(b.topRows(q1));
  if (q2 == 0) return y1;
  x.bottomRows(q2) = schur_a_.solve(b.bottomRows(q2) - c_ * y1);
  x.topRows(q1) = y1 - w_ * x.bottomRows(q2);
  return x;
}

double Deviance::operator()(const Eigen::VectorXd& theta) {
  solve(theta);
  const auto n = static_cast<double>(model_.y.size());
  const auto p = static_cast<double>(beta_.size());
  const double two_pi = 2.0 * std::numbers::pi;
  if (!reml_) return log_det_l_ + n * (1.0 + std::log(two_pi * pwrss_ / n));
  return log_det_l_ + log_det_rx_ + (n - p) * (1.0 + std::log(two_pi * pwrss_ / (n - p)));
}

double Deviance::atSigma(const Eigen::VectorXd& theta, double sigma) {
  solve(theta);
  const auto n = static_cast<double>(model_.y.size());
  const auto p = static_cast<double>(beta_.size());
  const double sigma2 = sigma * sigma;
  const double log_two_pi_sigma2 = std::log(2.0 * std::numbers::pi * sigma2);
  const double ml = log_det_l_ + pwrss_ / sigma2 + n * log_two_pi_sigma2;
  return reml_ ? ml + log_det_rx_ - p * log_two_pi_sigma2 : ml;
}

Eigen::MatrixXd Deviance::covarianceOfBeta(const Eigen::VectorXd& theta, double sigma) {
  solve(theta);
  const auto p = schur_.rows();
  return sigma * sigma * schur_.llt().solve(Eigen::MatrixXd::Identity(p, p));
}

double Deviance::sigmaHat() const {
  const auto n = static_cast<double>(model_.y.size());
  const auto p = static_cast<double>(beta_.size());
  return std::sqrt(pwrss_ / (reml_ ? n - p : n));
}

// ---- Bounded Nelder-Mead ------------------------------------------------------------

namespace {

/// One run of Nelder-Mead from `start` with initial steps `step`; points are projected
/// onto the bounds. Stops when the simplex's values agree to `f_tolerance` and its
/// vertices to `x_tolerance`, or after `budget` evaluations.
template <class F>
Minimum nelderMeadRun(F& f, const Eigen::VectorXd& start, double step, const std::vector<double>& lower,
                      std::size_t budget) {
  const auto k = start.size();
  const auto project = [&](Eigen::VectorXd x) {
    for (Eigen::Index i = 0; i < k; ++i) x[i] = std::max(x[i], lower[static_cast<std::size_t>(i)]);
    return x;
  };
  std::vector<Eigen::VectorXd> points{project(start)};
  for (Eigen::Index i = 0; i < k; ++i) {
    Eigen::VectorXd p = start;
    p[i] += step;
    points.push_back(project(p));
  }
  std::vector<double> values;
  for (const auto& p : points) values.push_back(f(p));
  std::size_t used = points.size();
  std::vector<std::size_t> order(points.size());
  for (;;) {
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
    const std::size_t best = order.front();
    const std::size_t worst = order.back();
    const std::size_t second = order[order.size() - 2];
    double spread = 0.0;
    for (const auto& p : points) spread = std::max(spread, (p - points[best]).cwiseAbs().maxCoeff());
    const double f_spread = values[worst] - values[best];
    if ((f_spread <= 1e-13 * (1.0 + std::abs(values[best])) && spread <= 1e-10) || used >= budget) {
      return {points[best], values[best], used < budget};
    }
    Eigen::VectorXd centroid = Eigen::VectorXd::Zero(k);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (i != worst) centroid += points[i];
    }
    centroid /= static_cast<double>(k);
    const auto evaluate = [&](const Eigen::VectorXd& p) {
      ++used;
      return f(p);
    };
    const Eigen::VectorXd reflected = project(centroid + (centroid - points[worst]));
    const double f_reflected = evaluate(reflected);
    if (f_reflected < values[best]) {
      const Eigen::VectorXd expanded = project(centroid + 2.0 * (centroid - points[worst]));
      const double f_expanded = evaluate(expanded);
      if (f_expanded < f_reflected) {
        points[worst] = expanded;
        values[worst] = f_expanded;
      } else {
        points[worst] = reflected;
        values[worst] = f_reflected;
      }
      continue;
    }
    if (f_reflected < values[second]) {
      points[worst] = reflected;
      values[worst] = f_reflected;
      continue;
    }
    // Contract towards the better of the worst point and its reflection.
    const bool outside = f_reflected < values[worst];
    const Eigen::VectorXd contracted =
        project(outside ? Eigen::VectorXd(centroid + 0.5 * (reflected - centroid))
                        : Eigen::VectorXd(centroid + 0.5 * (points[worst] - centroid)));
    const double f_contracted = evaluate(contracted);
    if (f_contracted < std::min(f_reflected, values[worst])) {
      points[worst] = contracted;
      values[worst] = f_contracted;
      continue;
    }
    // Shrink towards the best point.
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (i == best) continue;
      points[i] = project(points[best] + 0.5 * (points[i] - points[best]));
      values[i] = evaluate(points[i]);
    }
  }
}

}  // namespace

template <class F>
Minimum minimizeNelderMead(F&& f, Eigen::VectorXd start, const std::vector<double>& lower) {
  constexpr std::size_t kBudget = 100000;
  Minimum best = nelderMeadRun(f, start, 0.25, lower, kBudget);
  // Restart from the best point until a restart no longer improves: Nelder-Mead can stall
  // on a degenerate simplex.
  for (int restart = 0; restart < 20; ++restart) {
    const Minimum again = nelderMeadRun(f, best.x, 0.01, lower, kBudget);
    const bool improved = again.value < best.value - 1e-12 * (1.0 + std::abs(best.value));
    if (again.value <= best.value) best = again;
    if (!improved) break;
  }
  return best;
}

}  // namespace lmm

// ---- The fit ------------------------------------------------------------------------

namespace {

using lmm::Model;
using lmm::RandomBlock;

/// Each block's relative covariance factor T (lower triangular) from θ.
Eigen::MatrixXd blockFactor(const RandomBlock& b, const Eigen::VectorXd& theta) {
  const auto r = static_cast<Eigen::Index>(b.size());
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(r, r);
  auto index = static_cast<Eigen::Index>(b.theta_offset);
  for (Eigen::Index c = 0; c < r; ++c) {
    for (Eigen::Index row = c; row < r; ++row) t(row, c) = theta[index++];
  }
  return t;
}

/// Standard deviations and correlations, as R's as.data.frame(VarCorr(fit)).
void addVarianceComponents(const Model& m, const Eigen::VectorXd& theta, double sigma, LmmFit& fit) {
  std::vector<LmmVarianceComponent> correlations;
  for (const RandomBlock& b : m.blocks) {
    const Eigen::MatrixXd t = blockFactor(b, theta);
    const Eigen::MatrixXd cov = sigma * sigma * t * t.transpose();
    const auto r = static_cast<std::size_t>(cov.rows());
    for (std::size_t i = 0; i < r; ++i) {
      fit.variances.push_back({b.group_name, b.effects[i], "", std::sqrt(cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)))});
    }
    for (std::size_t c = 0; c < r; ++c) {
      for (std::size_t row = c + 1; row < r; ++row) {
        const auto ri = static_cast<Eigen::Index>(row);
        const auto ci = static_cast<Eigen::Index>(c);
        const double denominator = std::sqrt(cov(ri, ri) * cov(ci, ci));
        const double value = denominator > 0.0 ? cov(ri, ci) / denominator : std::numeric_limits<double>::quiet_NaN();
        fit.variances.push_back({b.group_name, b.effects[c], b.effects[row], value});
      }
    }
    fit.groups.push_back({b.group_name, b.levels});
  }
  fit.variances.push_back({"Residual", "", "", sigma});
}

/// lme4's isSingular(): a θ on its lower bound of 0 (to 1e-4), which is a variance of zero
/// or a correlation of ±1.
void flagSingularity(const Model& m, const Eigen::VectorXd& theta, LmmFit& fit) {
  for (const RandomBlock& b : m.blocks) {
    const auto r = b.size();
    std::size_t index = b.theta_offset;
    for (std::size_t c = 0; c < r; ++c) {
      for (std::size_t row = c; row < r; ++row, ++index) {
        if (row != c || theta[static_cast<Eigen::Index>(index)] >= 1e-4) continue;
        fit.singular = true;
        fit.warnings.push_back(fmt::format(
            "boundary (singular) fit: the random effect '{}' of '{}' has a variance of zero{} (θ = {:.3g}); the data do "
            "not support it, so simplify the random effects (drop it) before reading the fixed effects' tests",
            b.effects[c], b.group_name, r > 1 ? " or a correlation of ±1 with another" : "",
            theta[static_cast<Eigen::Index>(index)]));
      }
    }
  }
}

}  // namespace

LmmFit fitLmm(const DataTable& data, std::string_view formula, const LmmOptions& options) {
  const lmm::ParsedFormula parsed = lmm::parseFormula(formula);
  const Model m = lmm::buildModel(data, parsed, options);
  lmm::Deviance deviance(m, options.reml);

  // θ from lme4's start: identity relative factors.
  Eigen::VectorXd start = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m.theta_size));
  for (std::size_t i = 0; i < m.theta_size; ++i) {
    if (m.theta_lower[i] == 0.0) start[static_cast<Eigen::Index>(i)] = 1.0;
  }
  const lmm::Minimum best = lmm::minimizeNelderMead([&](const Eigen::VectorXd& t) { return deviance(t); }, start, m.theta_lower);

  LmmFit fit;
  fit.formula = std::string(formula);
  fit.response = parsed.response;
  fit.reml = options.reml;
  fit.observations = static_cast<std::size_t>(m.y.size());
  fit.data_columns = parsed.variables;
  fit.data_columns.insert(fit.data_columns.begin(), parsed.response);
  fit.criterion = deviance(best.x);  // leaves the solution at the optimum
  fit.evaluations = deviance.evaluations();
  if (!best.converged) fit.warnings.emplace_back("the optimizer reached its evaluation limit before converging");
  const Eigen::VectorXd beta = deviance.beta();
  fit.sigma = deviance.sigmaHat();
  fit.theta.assign(best.x.data(), best.x.data() + best.x.size());
  fit.log_likelihood = -fit.criterion / 2.0;
  fit.parameters = static_cast<std::size_t>(beta.size()) + m.theta_size + 1;
  fit.aic = fit.criterion + 2.0 * static_cast<double>(fit.parameters);
  fit.bic = fit.criterion + static_cast<double>(fit.parameters) * std::log(static_cast<double>(fit.observations));
  addVarianceComponents(m, best.x, fit.sigma, fit);
  flagSingularity(m, best.x, fit);
  if (!m.dropped.empty()) {
    std::string names;
    for (const std::string& d : m.dropped) names += (names.empty() ? "" : ", ") + d;
    fit.warnings.push_back(fmt::format("the fixed-effects matrix is rank deficient (an empty cell?): dropped {}", names));
  }

  for (Eigen::Index i = 0; i < beta.size(); ++i) {
    fit.fixed.push_back({m.fixed.names[static_cast<std::size_t>(i)], beta[i]});
  }
  if (!options.tests) return fit;

  // Satterthwaite's degrees of freedom for each coefficient and each term (lmerTest).
  lmm::Satterthwaite s = lmm::satterthwaite(deviance, best.x, fit.sigma);
  fit.warnings.insert(fit.warnings.end(), s.warnings.begin(), s.warnings.end());
  for (Eigen::Index i = 0; i < beta.size(); ++i) {
    Eigen::RowVectorXd l = Eigen::RowVectorXd::Zero(beta.size());
    l[i] = 1.0;
    lmm::testContrast(s, beta, l, fit.fixed[static_cast<std::size_t>(i)]);
  }
  const std::vector<Eigen::MatrixXd> hypotheses = lmm::typeThreeHypotheses(m);
  for (std::size_t t = 0; t < hypotheses.size(); ++t) {
    // A term whose columns were all dropped cannot be tested: NaN, as R's NA.
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    LmmTermTest test{"", kNaN, kNaN, kNaN, kNaN};
    if (hypotheses[t].rows() > 0) test = lmm::testHypothesis(s, beta, hypotheses[t]);
    test.term = lmm::termLabel(parsed, parsed.fixed[t]);
    fit.terms.push_back(test);
  }
  return fit;
}

LikelihoodRatioTest likelihoodRatio(const LmmFit& smaller, const LmmFit& larger) {
  HATTR_THROW_UNLESS(!smaller.reml && !larger.reml, "likelihood-ratio test of '{}' and '{}': both models must be fitted "
                     "by maximum likelihood (REML criteria of different fixed effects are not comparable); fit with --ml",
                     smaller.formula, larger.formula);
  HATTR_THROW_UNLESS(smaller.observations == larger.observations && smaller.response == larger.response,
                     "likelihood-ratio test: '{}' ({} observations of {}) and '{}' ({} of {}) are not fitted to the same data",
                     smaller.formula, smaller.observations, smaller.response, larger.formula, larger.observations,
                     larger.response);
  HATTR_THROW_UNLESS(larger.parameters > smaller.parameters, "likelihood-ratio test: '{}' has {} parameters, '{}' {}; "
                     "a likelihood-ratio test needs nested models of different sizes, the smaller first",
                     smaller.formula, smaller.parameters, larger.formula, larger.parameters);
  LikelihoodRatioTest t;
  t.smaller = smaller.formula;
  t.larger = larger.formula;
  t.chi_sq = std::max(0.0, smaller.criterion - larger.criterion);
  t.df = larger.parameters - smaller.parameters;
  t.p = boost::math::cdf(boost::math::complement(boost::math::chi_squared(static_cast<double>(t.df)), t.chi_sq));
  return t;
}

DataTable dataTableFromText(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                            std::string source) {
  DataTable t;
  t.source = std::move(source);
  for (const std::string& name : header) t.columns.push_back({name, {}, {}});
  for (const auto& row : rows) {
    HATTR_DEMAND(row.size() == header.size(), "a row of {} has {} cells for {} columns", t.source, row.size(), header.size());
    for (std::size_t c = 0; c < row.size(); ++c) t.columns[c].text.push_back(row[c]);
  }
  return t;
}

std::vector<LikelihoodRatioTest> compareLmms(const DataTable& data, const std::vector<std::string>& formulas,
                                             const LmmOptions& options) {
  HATTR_THROW_UNLESS(formulas.size() >= 2, "comparing models: expected at least two formulas, got {}", formulas.size());
  LmmOptions ml = options;
  ml.reml = false;
  ml.tests = false;
  std::vector<LmmFit> fits;
  for (const std::string& f : formulas) fits.push_back(fitLmm(data, f, ml));
  std::stable_sort(fits.begin(), fits.end(), [](const LmmFit& a, const LmmFit& b) { return a.parameters < b.parameters; });
  std::vector<LikelihoodRatioTest> out;
  for (std::size_t i = 1; i < fits.size(); ++i) out.push_back(likelihoodRatio(fits[i - 1], fits[i]));
  return out;
}

nlohmann::json toJson(const LmmFit& fit) {
  nlohmann::json fixed = nlohmann::json::array();
  for (const LmmCoefficient& c : fit.fixed) {
    fixed.push_back({{"name", c.name}, {"estimate", jsonNumber(c.estimate)}, {"std_error", jsonNumber(c.std_error)},
                     {"df", jsonNumber(c.df)}, {"t", jsonNumber(c.t)}, {"p", jsonNumber(c.p)},
                     {"lower", jsonNumber(c.lower)}, {"upper", jsonNumber(c.upper)}});
  }
  nlohmann::json terms = nlohmann::json::array();
  for (const LmmTermTest& t : fit.terms) {
    terms.push_back({{"term", t.term}, {"num_df", jsonNumber(t.num_df)}, {"den_df", jsonNumber(t.den_df)}, {"f", jsonNumber(t.f)},
                     {"p", jsonNumber(t.p)}});
  }
  nlohmann::json variances = nlohmann::json::array();
  for (const LmmVarianceComponent& v : fit.variances) {
    nlohmann::json row = {{"group", v.group}, {"effect", v.effect}};
    if (v.other.empty()) {
      row["std_dev"] = jsonNumber(v.value);
      row["variance"] = jsonNumber(v.value * v.value);
    } else {
      row["with"] = v.other;
      row["correlation"] = jsonNumber(v.value);
    }
    variances.push_back(row);
  }
  nlohmann::json groups = nlohmann::json::array();
  for (const LmmGroup& g : fit.groups) groups.push_back({{"name", g.name}, {"levels", g.levels}});
  return {{"formula", fit.formula}, {"response", fit.response}, {"method", fit.reml ? "REML" : "ML"},
          {"observations", fit.observations}, {"groups", groups}, {"fixed_effects", fixed}, {"terms", terms},
          {"random_effects", variances}, {"sigma", jsonNumber(fit.sigma)}, {"theta", fit.theta},
          {fit.reml ? "reml_criterion" : "deviance", jsonNumber(fit.criterion)}, {"log_likelihood", jsonNumber(fit.log_likelihood)},
          {"aic", jsonNumber(fit.aic)}, {"bic", jsonNumber(fit.bic)}, {"parameters", fit.parameters}, {"singular", fit.singular},
          {"warnings", fit.warnings}, {"evaluations", fit.evaluations}, {"df_method", "Satterthwaite"}};
}

nlohmann::json toJson(const LikelihoodRatioTest& t) {
  return {{"smaller", t.smaller}, {"larger", t.larger}, {"chi_sq", jsonNumber(t.chi_sq)}, {"df", t.df}, {"p", jsonNumber(t.p)}};
}

}  // namespace hattr::analysis
