// Vectorized DTW kernels (Highway). foreach_target.h compiles this file once per
// instruction set (SSSE3, SSE4, AVX2, AVX-512, plus the baseline) and HWY_DYNAMIC_DISPATCH
// picks the best one the CPU supports at run time, so one binary runs everywhere.
// foreach_target.h re-includes this file by the name below: src/ must be on the include
// path of this translation unit (see the CMake lines in docs/analysis.md).
//
// The batch kernel (one pair's is in dtw_pair_simd.cpp):
//  - batchKernel: many pairs of equal lengths. SIMD lanes are different pairs; D is computed
//    in strips of rows, column by column, so a block's full-width row of D is read and
//    written once per strip; four vectors of pairs are interleaved to hide the latency of
//    the sequential dependency down each column of a strip. Cells that cannot lie on the
//    best path are skipped (pruned DTW, Silva & Batista 2016): each pair's cost along one
//    simple path bounds its DTW cost, and a strip's columns left and right of every cell
//    within the bound are not computed. The cells within it are computed exactly as
//    without pruning, so the costs are the same to the bit.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "analysis/dtw_simd.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>
#include <vector>

#include "analysis/dtw_cost-inl.h"
#include "dtw_internal.hpp"

HWY_BEFORE_NAMESPACE();
namespace hattr::analysis::detail {
namespace HWY_NAMESPACE {
constexpr std::size_t kBatchGroups = 4;  // vectors of pairs per batch block

// One cell D(i, j) of one vector of pairs, inside a strip of rows: `up` is D(i-1, j), `diag`
// D(i-1, j-1), and `left` (in L1) holds the row's D(i, j-1), which the cell replaces; `diag`
// becomes that old value, the next row's diagonal. Returns the cell: the next row's `up`.
template <DtwCost kCost>
HWY_INLINE Vd stripCell(Tag d, Vd a_i, Vd b_j, Vd up, Vd& diag, double* left) {
  const Vd old = hn::LoadU(d, left);
  const Vd value = hn::Add(localCost<kCost>(a_i, b_j), hn::Min(up, hn::Min(diag, old)));
  diag = old;
  hn::StoreU(value, d, left);
  return value;
}

// A cell outside the band: +inf, with the same hand-over of `left` and `diag` as stripCell.
HWY_INLINE Vd stripCellOutside(Tag d, Vd& diag, double* left) {
  diag = hn::LoadU(d, left);
  const Vd inf = hn::Set(d, kInf);
  hn::StoreU(inf, d, left);
  return inf;
}

constexpr std::size_t kStripRows = 16;  // rows of D computed together, column by column
// The narrow band whose costs bound a wide problem's (pruning): a twentieth of the length.
constexpr std::size_t kPrepassBand(std::size_t longer) { return (longer + 19) / 20; }

// The pruning threshold of one pair: its cost along the path that goes diagonally, then
// straight to the corner (inside any band, which covers |n - m|), accumulated in the
// kernels' order so that D(n-1, m-1) <= it, plus a margin for a compiler's different
// rounding (fused multiply-adds): every cell above it is off the best path.
template <DtwCost kCost>
double pathBound(const double* a, const double* b, std::size_t n, std::size_t m) {
  const auto cost = [&](std::size_t i, std::size_t j) {
    const double diff = a[i] - b[j];
    return kCost == DtwCost::kAbsolute ? std::abs(diff) : diff * diff;
  };
  double sum = cost(0, 0);
  for (std::size_t i = 0, j = 0; i + 1 < n || j + 1 < m;) {
    if (i + 1 < n) ++i;
    if (j + 1 < m) ++j;
    sum = cost(i, j) + sum;
  }
  return sum * (1.0 + 4.0 * static_cast<double>(n + m) * std::numeric_limits<double>::epsilon());
}

// Whether any lane of the four vectors is within its pair's threshold.
HWY_INLINE bool anyWithin(Tag d, const double* v, const double* threshold) {
  const std::size_t lanes = hn::Lanes(d);
  auto within = hn::Le(hn::LoadU(d, v), hn::LoadU(d, threshold));
  for (std::size_t g = 1; g < kBatchGroups; ++g) {
    within = hn::Or(within, hn::Le(hn::LoadU(d, v + g * lanes), hn::LoadU(d, threshold + g * lanes)));
  }
  return !hn::AllFalse(d, within);
}

// Many univariate pairs of equal lengths; lane s of the block holds pair block + s.
// Series are interleaved (element i of every pair of the block side by side). D is computed
// in strips of kStripRows rows, column by column: each column's b_j is loaded once for the
// strip, the strip's rows keep their D(i, j-1) in a small buffer in L1, and the full-width
// row of D (the strip's last row, the next strip's top) is read and written once per strip,
// not once per row: the block stays within the core's own caches. Four vectors of pairs
// advance together, so the chain down a column overlaps four ways. Every cell is the same
// expression as the other kernels', so the costs do not depend on the order.
//
// Pruning: a cell above its pair's threshold (pathBound) is off the best path, and so is
// every cell whose three predecessors all are. A strip starts at the first column where the
// row above it has a cell within some pair's threshold (left of it every cell of the strip
// is above), and stops after a column that is wholly above while the row above is too
// (right of it, all are). Cells left out read as +inf, which changes only cells above the
// threshold: those within it are exact.
template <DtwCost kCost, bool kAbandon>
void batchKernel(const KernelProblem& p, double* out);

// The block's thresholds lowered to its pairs' costs within a narrow band, when the problem's
// band is much wider: a path in the narrow band is a path in the wide one, computed by the
// same cells, so the full cost never exceeds it.
template <DtwCost kCost>
void tightenThresholds(const KernelProblem& p, std::size_t block, std::size_t width, double* threshold) {
  const std::size_t longer = std::max(p.n, p.m);
  const std::size_t narrow = std::max(kPrepassBand(longer), longer - std::min(p.n, p.m));
  if (std::min(p.radius, longer) <= 2 * narrow) return;
  KernelProblem q = p;
  q.a = p.a + block;
  q.b = p.b + block;
  q.count = std::min(width, p.count - block);
  q.radius = narrow;
  q.bound = kInf;
  std::vector<double> banded(q.count);
  batchKernel<kCost, false>(q, banded.data());
  for (std::size_t s = 0; s < width; ++s) {
    const double cost = banded[std::min(s, q.count - 1)];
    const double margin = 4.0 * static_cast<double>(p.n + p.m) * std::numeric_limits<double>::epsilon();
    threshold[s] = std::min(threshold[s], cost * (1.0 + margin));
  }
}

// One block of batchKernel: its interleaved series, the full-width row of D (the last row of
// the strip above), the strip's rows' D(i, j-1), the pairs' thresholds, and the sizes.
struct BatchBlock {
  std::size_t n = 0;
  std::size_t m = 0;
  std::size_t r = 0;      // the band's radius
  std::size_t width = 0;  // pairs in the block: kBatchGroups vectors
  const double* a_int = nullptr;
  const double* b_int = nullptr;
  double* row = nullptr;
  double* left = nullptr;
  const double* threshold = nullptr;
};

// The columns [first, last] of the row above a strip that were computed; the others are above
// every threshold. Above the first strip: only D(-1, -1) = 0.
struct ComputedColumns {
  std::size_t first = 0;
  std::size_t last = 0;
};

// Row i of a strip column, k rows below the strip's top: its four vectors of cells, inside the
// band or (kInBand false) outside it. Each hands on up (the cell just computed) and diag (the
// next row's D(i-1, j-1)); with kTrack, the column's smallest cells too. (Vectors are passed
// one by one: sizeless vector types, as on SVE, cannot be members of a struct.)
template <DtwCost kCost, bool kTrack, bool kInBand>
HWY_INLINE void stripRow(Tag d, const BatchBlock& blk, std::size_t i, std::size_t k, Vd b0, Vd b1, Vd b2, Vd b3,
                         Vd& up0, Vd& up1, Vd& up2, Vd& up3, Vd& diag0, Vd& diag1, Vd& diag2, Vd& diag3,
                         Vd& column0, Vd& column1, Vd& column2, Vd& column3) {
  const std::size_t lanes = hn::Lanes(d);
  double* l = blk.left + k * blk.width;
  if constexpr (kInBand) {
    const double* a_i = blk.a_int + i * blk.width;
    up0 = stripCell<kCost>(d, hn::LoadU(d, a_i), b0, up0, diag0, l);
    up1 = stripCell<kCost>(d, hn::LoadU(d, a_i + lanes), b1, up1, diag1, l + lanes);
    up2 = stripCell<kCost>(d, hn::LoadU(d, a_i + 2 * lanes), b2, up2, diag2, l + 2 * lanes);
    up3 = stripCell<kCost>(d, hn::LoadU(d, a_i + 3 * lanes), b3, up3, diag3, l + 3 * lanes);
  } else {
    up0 = stripCellOutside(d, diag0, l);
    up1 = stripCellOutside(d, diag1, l + lanes);
    up2 = stripCellOutside(d, diag2, l + 2 * lanes);
    up3 = stripCellOutside(d, diag3, l + 3 * lanes);
  }
  if constexpr (kTrack) {
    column0 = hn::Min(column0, up0);
    column1 = hn::Min(column1, up1);
    column2 = hn::Min(column2, up2);
    column3 = hn::Min(column3, up3);
  }
}

// One column j of a strip, down its `rows` rows from i0: each cell from its up, diagonal and
// left, or +inf outside the band; with kTrack also the column's smallest cells (to find where
// the strip may stop). A full strip wholly inside the band (every strip without a band) runs
// unrolled, without a test per row.
template <DtwCost kCost, bool kTrack>
HWY_INLINE void stripColumn(Tag d, const BatchBlock& blk, std::size_t i0, std::size_t rows, std::size_t j, Vd b0, Vd b1,
                            Vd b2, Vd b3, Vd& up0, Vd& up1, Vd& up2, Vd& up3, Vd& diag0, Vd& diag1, Vd& diag2,
                            Vd& diag3, Vd& column0, Vd& column1, Vd& column2, Vd& column3) {
  if (rows == kStripRows && j + blk.r >= i0 + kStripRows - 1 && j <= i0 + blk.r) {
#pragma GCC unroll 16
    for (std::size_t k = 0; k < kStripRows; ++k) {
      stripRow<kCost, kTrack, true>(d, blk, i0 + k, k, b0, b1, b2, b3, up0, up1, up2, up3, diag0, diag1, diag2, diag3,
                                    column0, column1, column2, column3);
    }
    return;
  }
  for (std::size_t k = 0; k < rows; ++k) {
    const std::size_t i = i0 + k;
    if (j + blk.r >= i && j <= i + blk.r) {  // |i - j| <= r
      stripRow<kCost, kTrack, true>(d, blk, i, k, b0, b1, b2, b3, up0, up1, up2, up3, diag0, diag1, diag2, diag3,
                                    column0, column1, column2, column3);
    } else {
      stripRow<kCost, kTrack, false>(d, blk, i, k, b0, b1, b2, b3, up0, up1, up2, up3, diag0, diag1, diag2, diag3,
                                     column0, column1, column2, column3);
    }
  }
}

// The strip's first column and the last column of the row above with a cell within a
// threshold: from its first row's band, and from the first column where the row above has a
// cell within a threshold (left of them every row's D(i, j-1) is outside the band or above the
// thresholds: +inf). The strip may stop once it is right of that last column.
HWY_INLINE std::pair<std::size_t, std::size_t> stripStart(Tag d, const BatchBlock& blk, std::size_t i0, bool first_strip,
                                                          const ComputedColumns& above) {
  const std::size_t width = blk.width;
  std::size_t j_first = i0 > blk.r ? i0 - blk.r : 0;
  std::size_t above_within_last = 0;
  if (!first_strip) {
    std::size_t start = above.first;
    while (start < above.last && !anyWithin(d, blk.row + start * width, blk.threshold)) ++start;
    j_first = std::max(j_first, start);
    above_within_last = above.last;
    while (above_within_last > start && !anyWithin(d, blk.row + above_within_last * width, blk.threshold)) {
      --above_within_last;
    }
  }
  return {j_first, above_within_last};
}

// One strip of kStripRows rows from i0, column by column (batchKernel); `above` becomes its own
// computed columns. Returns whether every lane's strip row exceeds the bound (kAbandon).
template <DtwCost kCost, bool kAbandon>
HWY_INLINE bool computeStrip(Tag d, const BatchBlock& blk, double bound, std::size_t i0, bool first_strip,
                             ComputedColumns& above) {
  const std::size_t lanes = hn::Lanes(d);
  const std::size_t width = blk.width;
  const Vd inf = hn::Set(d, kInf);
  const Vd th0 = hn::LoadU(d, blk.threshold), th1 = hn::LoadU(d, blk.threshold + lanes);
  const Vd th2 = hn::LoadU(d, blk.threshold + 2 * lanes), th3 = hn::LoadU(d, blk.threshold + 3 * lanes);
  const std::size_t rows = std::min(kStripRows, blk.n - i0);
  const std::size_t i_last = i0 + rows - 1;
  const auto [j_first, above_within_last] = stripStart(d, blk, i0, first_strip, above);
  const std::size_t j_last = std::min(blk.m - 1, i_last + blk.r);
  std::fill(blk.left, blk.left + rows * width, kInf);
  // D(i0-1, j_first-1), the first row's diagonal: D(-1, -1) = 0 on row 0; +inf left of
  // column 0 and where the row above was not computed.
  Vd top0 = first_strip && j_first == 0 ? hn::Zero(d) : inf;
  Vd top1 = top0, top2 = top0, top3 = top0;
  if (!first_strip && j_first > above.first && j_first - 1 <= above.last) {
    const double* c = blk.row + (j_first - 1) * width;
    top0 = hn::LoadU(d, c), top1 = hn::LoadU(d, c + lanes);
    top2 = hn::LoadU(d, c + 2 * lanes), top3 = hn::LoadU(d, c + 3 * lanes);
  }
  Vd min0 = inf, min1 = inf, min2 = inf, min3 = inf;
  std::size_t j = j_first;
  for (; j <= j_last; ++j) {
    const double* b_j = blk.b_int + j * width;
    // Down the column: up starts as D(i0-1, j) from the row above the strip (+inf where
    // it was not computed).
    double* cell = blk.row + j * width;
    const bool above_computed = !first_strip && j >= above.first && j <= above.last;
    Vd up0 = above_computed ? hn::LoadU(d, cell) : inf;
    Vd up1 = above_computed ? hn::LoadU(d, cell + lanes) : inf;
    Vd up2 = above_computed ? hn::LoadU(d, cell + 2 * lanes) : inf;
    Vd up3 = above_computed ? hn::LoadU(d, cell + 3 * lanes) : inf;
    Vd diag0 = top0, diag1 = top1, diag2 = top2, diag3 = top3;
    top0 = up0;
    top1 = up1;
    top2 = up2;
    top3 = up3;
    // Down the strip; right of the row above's last cell within a threshold, also the
    // column's smallest cells, to find where the strip may stop.
    Vd column0 = inf, column1 = inf, column2 = inf, column3 = inf;
    const bool right_of_above = first_strip || j > above_within_last;
    const Vd b0 = hn::LoadU(d, b_j), b1 = hn::LoadU(d, b_j + lanes);
    const Vd b2 = hn::LoadU(d, b_j + 2 * lanes), b3 = hn::LoadU(d, b_j + 3 * lanes);
    if (right_of_above) {
      stripColumn<kCost, true>(d, blk, i0, rows, j, b0, b1, b2, b3, up0, up1, up2, up3, diag0, diag1, diag2, diag3,
                               column0, column1, column2, column3);
    } else {
      stripColumn<kCost, false>(d, blk, i0, rows, j, b0, b1, b2, b3, up0, up1, up2, up3, diag0, diag1, diag2, diag3,
                                column0, column1, column2, column3);
    }
    // The strip's last row becomes the row above the next strip.
    hn::StoreU(up0, d, cell);
    hn::StoreU(up1, d, cell + lanes);
    hn::StoreU(up2, d, cell + 2 * lanes);
    hn::StoreU(up3, d, cell + 3 * lanes);
    if constexpr (kAbandon) {
      min0 = hn::Min(min0, up0);
      min1 = hn::Min(min1, up1);
      min2 = hn::Min(min2, up2);
      min3 = hn::Min(min3, up3);
    }
    // There, a column wholly above the thresholds ends the strip: the next column's up,
    // diagonal and left are all above them.
    if (right_of_above) {
      const auto within = hn::Or(hn::Or(hn::Le(column0, th0), hn::Le(column1, th1)),
                                 hn::Or(hn::Le(column2, th2), hn::Le(column3, th3)));
      if (hn::AllFalse(d, within)) break;
    }
  }
  above = {j_first, std::min(j, j_last)};
  // Every path crosses the strip's last row: stop when all lanes' rows exceed the bound.
  if constexpr (kAbandon) {
    const Vd all = hn::Min(hn::Min(min0, min1), hn::Min(min2, min3));
    return hn::GetLane(hn::MinOfLanes(d, all)) > bound;
  }
  return false;
}

template <DtwCost kCost, bool kAbandon>
void batchKernel(const KernelProblem& p, double* out) {
  const Tag d;
  const std::size_t width = kBatchGroups * hn::Lanes(d);
  const std::size_t n = p.n;
  const std::size_t m = p.m;
  std::vector<double> a_int(n * width);
  std::vector<double> b_int(m * width);
  std::vector<double> row(m * width);
  std::vector<double> left(kStripRows * width);
  std::vector<double> threshold(width);
  const BatchBlock blk{.n = n, .m = m, .r = std::min(p.radius, std::max(n, m)), .width = width, .a_int = a_int.data(),
                       .b_int = b_int.data(), .row = row.data(), .left = left.data(), .threshold = threshold.data()};

  for (std::size_t block = 0; block < p.count; block += width) {
    // Interleave the block's pairs; lanes past the last pair repeat it (results dropped).
    for (std::size_t s = 0; s < width; ++s) {
      const std::size_t pair = std::min(block + s, p.count - 1);
      for (std::size_t i = 0; i < n; ++i) a_int[i * width + s] = p.a[pair][i];
      for (std::size_t j = 0; j < m; ++j) b_int[j * width + s] = p.b[pair][j];
      threshold[s] = pathBound<kCost>(p.a[pair], p.b[pair], n, m);
    }
    tightenThresholds<kCost>(p, block, width, threshold.data());

    ComputedColumns above;
    bool first_strip = true;
    bool abandoned = false;
    for (std::size_t i0 = 0; i0 < n && !abandoned; i0 += kStripRows, first_strip = false) {
      abandoned = computeStrip<kCost, kAbandon>(d, blk, p.bound, i0, first_strip, above);
    }

    // The corner was computed unless the last strip stopped before it (then it is above
    // every threshold, which no pair's cost is: unreachable, but never read stale).
    const double* last = row.data() + (m - 1) * width;
    for (std::size_t s = 0; s < width && block + s < p.count; ++s) {
      const bool corner_computed = above.last == m - 1;
      out[block + s] = abandoned || !corner_computed || last[s] > p.bound ? kInf : last[s];
    }
  }
}


void batchDtwTarget(const KernelProblem& p, double* out) {
  const bool abandon = p.bound < kInf;
  if (p.cost == DtwCost::kAbsolute) {
    abandon ? batchKernel<DtwCost::kAbsolute, true>(p, out)
            : batchKernel<DtwCost::kAbsolute, false>(p, out);
  } else {
    abandon ? batchKernel<DtwCost::kSquared, true>(p, out)
            : batchKernel<DtwCost::kSquared, false>(p, out);
  }
}

std::size_t batchWidthTarget() { return kBatchGroups * hn::Lanes(Tag()); }

const char* targetNameTarget() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace hattr::analysis::detail
HWY_AFTER_NAMESPACE();

// Once, after all targets: the dispatch tables and the functions dtw.cpp calls.
#if HWY_ONCE
namespace hattr::analysis::detail {

HWY_EXPORT(batchDtwTarget);
HWY_EXPORT(batchWidthTarget);
HWY_EXPORT(targetNameTarget);

void batchDtw(const KernelProblem& problem, double* out) {
  HWY_DYNAMIC_DISPATCH(batchDtwTarget)(problem, out);
}

std::size_t batchWidth() { return HWY_DYNAMIC_DISPATCH(batchWidthTarget)(); }

const char* simdTargetName() { return HWY_DYNAMIC_DISPATCH(targetNameTarget)(); }

}  // namespace hattr::analysis::detail
#endif  // HWY_ONCE
