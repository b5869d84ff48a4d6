#include "hattr/sim/basis.hpp"

#include <cmath>

#include "hattr/core/error.hpp"

namespace hattr::sim {

NormalizedGaussianBasis::NormalizedGaussianBasis(int count, double width_ratio)
    : count_(count), spacing_(count > 1 ? 1.0 / static_cast<double>(count - 1) : 1.0), sigma_(width_ratio * spacing_) {
  HATTR_THROW_UNLESS(count >= 2 && count <= 1000, "basis: count: expected an integer in [2, 1000], got {}", count);
  HATTR_THROW_UNLESS(std::isfinite(width_ratio) && width_ratio > 0.0 && width_ratio <= 10.0,
                     "basis: width_ratio: expected a number in (0, 10], got {}", width_ratio);
}

Eigen::VectorXd NormalizedGaussianBasis::values(double u) const {
  Eigen::VectorXd g(count_);
  for (int k = 0; k < count_; ++k) {
    const double d = (u - centre(k)) / sigma_;
    g(k) = std::exp(-0.5 * d * d);
  }
  return g / g.sum();
}

Eigen::VectorXd NormalizedGaussianBasis::derivatives(double u) const {
  Eigen::VectorXd g(count_);
  Eigen::VectorXd dg(count_);
  for (int k = 0; k < count_; ++k) {
    const double d = (u - centre(k)) / sigma_;
    g(k) = std::exp(-0.5 * d * d);
    dg(k) = -d / sigma_ * g(k);
  }
  const double sum = g.sum();
  const double dsum = dg.sum();
  // (g_k / S)' = (g_k' S − g_k S') / S²
  return (dg * sum - g * dsum) / (sum * sum);
}

Eigen::MatrixXd NormalizedGaussianBasis::design(const std::vector<double>& u) const {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(u.size()), count_);
  for (std::size_t i = 0; i < u.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = values(u[i]).transpose();
  return m;
}

Eigen::MatrixXd NormalizedGaussianBasis::designDerivative(const std::vector<double>& u) const {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(u.size()), count_);
  for (std::size_t i = 0; i < u.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = derivatives(u[i]).transpose();
  return m;
}

}  // namespace hattr::sim
