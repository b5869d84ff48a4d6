#pragma once
// Private to the sim module (and its tests): the trainee's plan series, combined from its basis.

#include <cstddef>
#include <initializer_list>

#include <Eigen/Core>

#include "hattr/sim/trainee.hpp"

namespace hattr::sim::detail {

/// The basis at every sample combined by the `columns` of `weights` (each of 0, 1, 2), one
/// result column each: (phi * weights).col(c) for each c, each entry summed over the basis
/// functions in turn from zero. Those are the sums, in that order, of Eigen's product of a matrix
/// by at most three columns whose depth fits one of its blocks, so the bits are the same
/// (trainee_test compares the two, on this build's Eigen and CPU); unlike the product, it does
/// not copy phi (N × K) into a packed block first, which was most of a plan's cost. Where Eigen's
/// product takes another path (one row, a tiny product, more than 128 basis functions): that
/// product itself.
Eigen::MatrixXd combineBasis(const Eigen::MatrixXd& phi, const PlanWeights& weights,
                             std::initializer_list<Eigen::Index> columns);

/// combineBasis's sums (basis_combine.cpp, vectorized): out[j][r] = the sum over k in turn, from
/// zero, of phi[k * rows + r] * weights[j][k], for j < columns (1 to 3).
struct BasisCombination {
  const double* phi = nullptr;  ///< rows x functions, by columns
  std::size_t rows = 0;
  std::size_t functions = 0;
  std::size_t columns = 0;
  const double* weights[3] = {};  ///< each `functions` long
  double* out[3] = {};            ///< each `rows` long
};
void combineBasisColumns(const BasisCombination& combination);

}  // namespace hattr::sim::detail
