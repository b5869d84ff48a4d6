#pragma once
/// Normalized Gaussian basis functions over normalized time u ∈ [0, 1]: the smooth space in
/// which a simulated trainee's movement and force plans, its motor noise and its learning
/// live (docs/simulation.md). Basis k is g_k(u) / Σ_j g_j(u) with g_k(u) = exp(−(u − c_k)² / 2σ²),
/// centres c_k evenly spaced from 0 to 1, σ = width_ratio × spacing. The functions sum to 1 at
/// every u, so a constant field has all weights equal to it.

#include <vector>

#include <Eigen/Core>

namespace hattr::sim {

class NormalizedGaussianBasis {
 public:
  /// `count` functions (2 to 1000), width σ = `width_ratio` × centre spacing (0 < ratio <= 10).
  /// Throws InputError otherwise.
  NormalizedGaussianBasis(int count, double width_ratio);

  [[nodiscard]] int size() const noexcept { return count_; }
  /// Centre of function k in normalized time.
  [[nodiscard]] double centre(int k) const noexcept { return static_cast<double>(k) * spacing_; }
  /// Spacing of the centres, 1 / (count − 1).
  [[nodiscard]] double spacing() const noexcept { return spacing_; }
  /// Width σ in normalized time.
  [[nodiscard]] double width() const noexcept { return sigma_; }

  /// Values of every function at u (they sum to 1).
  [[nodiscard]] Eigen::VectorXd values(double u) const;
  /// Derivatives d/du of every function at u (they sum to 0).
  [[nodiscard]] Eigen::VectorXd derivatives(double u) const;
  /// The design matrix: row i holds values(u[i]).
  [[nodiscard]] Eigen::MatrixXd design(const std::vector<double>& u) const;
  /// Row i holds derivatives(u[i]).
  [[nodiscard]] Eigen::MatrixXd designDerivative(const std::vector<double>& u) const;

 private:
  int count_;
  double spacing_;
  double sigma_;
};

}  // namespace hattr::sim
