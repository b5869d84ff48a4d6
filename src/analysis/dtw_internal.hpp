#pragma once
// Private interface between dtw.cpp (checks, paths, threads) and dtw_simd.cpp (the
// Highway kernels, compiled once per instruction set and chosen at run time).

#include <cstddef>

#include "hattr/analysis/dtw.hpp"

namespace hattr::analysis::detail {

/// One DTW problem for the kernels: a[s] points to n values and b[s] to m values, all
/// finite, n, m >= 1, s < count. For diagonalDtw the `count` entries are the channels of
/// one pair; for batchDtw they are `count` independent univariate pairs. Cells with
/// |i - j| > radius are excluded (radius >= |n - m|; kNoBand for none). Results above
/// `bound` become +infinity.
struct KernelProblem {
  const double* const* a = nullptr;
  const double* const* b = nullptr;
  std::size_t count = 1;
  std::size_t n = 0;
  std::size_t m = 0;
  std::size_t radius = kNoBand;
  DtwCost cost = DtwCost::kAbsolute;
  double bound = 0.0;
};

/// DTW cost of one (possibly multichannel) pair, vectorized over anti-diagonals.
double diagonalDtw(const KernelProblem& problem);

/// DTW costs of problem.count univariate pairs (a[p], b[p]) of equal lengths n, m, SIMD
/// lanes = pairs. Writes out[p] for p < count.
void batchDtw(const KernelProblem& problem, double* out);

/// Pairs per block of batchDtw (4 vectors of lanes); fewer pairs leave lanes idle.
std::size_t batchWidth();

/// Name of the instruction set the kernels dispatch to.
const char* simdTargetName();

/// One LB_Keogh: n values of the candidate against the envelope's sides (n values each).
struct LbProblem {
  const double* candidate = nullptr;
  const double* lower = nullptr;
  const double* upper = nullptr;
  std::size_t n = 0;
  bool squared = false;
  double abandon_above = 0.0;  ///< the sum is returned once it exceeds this (checked a block at a time)
};
double lbKeoghSimd(const LbProblem& problem);

/// A segment envelope's arrays (`size` values each).
struct SegmentEnvelopeView {
  const double* lower = nullptr;
  const double* upper = nullptr;
  const double* width = nullptr;
  std::size_t size = 0;
};
/// out[c] = Σ_s width[s] · gap(means[c · size + s], [lower[s], upper[s]]) for c < count.
void segmentBoundsSimd(const double* means, std::size_t count, const SegmentEnvelopeView& envelope, double* out);

}  // namespace hattr::analysis::detail
