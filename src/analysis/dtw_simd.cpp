// Vectorized DTW kernels (Highway). foreach_target.h compiles this file once per
// instruction set (SSSE3, SSE4, AVX2, AVX-512, plus the baseline) and HWY_DYNAMIC_DISPATCH
// picks the best one the CPU supports at run time, so one binary runs everywhere.
// foreach_target.h re-includes this file by the name below: src/ must be on the include
// path of this translation unit (see the CMake lines in docs/analysis.md).
//
// Two kernels:
//  - diagonalKernel: one pair. The cells of an anti-diagonal k = i + j depend only on the
//    two previous anti-diagonals, so a whole anti-diagonal is one stream of independent
//    SIMD operations. Three anti-diagonal buffers: O(band) memory.
//  - batchKernel: many pairs of equal lengths. SIMD lanes are different pairs; D is computed
//    in strips of rows, column by column, so a block's full-width row of D is read and
//    written once per strip; four vectors of pairs are interleaved to hide the latency of
//    the sequential dependency down each column of a strip.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "analysis/dtw_simd.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

#include "dtw_internal.hpp"

HWY_BEFORE_NAMESPACE();
namespace hattr::analysis::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using Tag = hn::ScalableTag<double>;
using Vd = hn::Vec<Tag>;
using Index = std::ptrdiff_t;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kBatchGroups = 4;  // vectors of pairs per batch block

// The local cost of lanes x and y; the same arithmetic as the scalar reference.
template <DtwCost kCost>
HWY_INLINE Vd localCost(Vd x, Vd y) {
  const Vd diff = hn::Sub(x, y);
  if constexpr (kCost == DtwCost::kAbsolute) {
    return hn::Abs(diff);
  } else {
    return hn::Mul(diff, diff);
  }
}

// The rows [lo, hi] of anti-diagonal k that lie in the n x m matrix and in the band
// |i - j| <= r (r >= |n - m|). Empty (lo > hi) only for r = 0 and odd k.
// lo and hi never decrease and grow by at most one from k to k + 1.
struct DiagonalRange {
  Index lo;
  Index hi;
};
HWY_INLINE DiagonalRange diagonalRange(Index k, Index n, Index m, Index r) {
  // (k - r + 1) / 2 truncates toward zero; for k - r + 1 <= 0 the result is <= 0, which
  // the max with 0 absorbs, so it acts as ceil((k - r) / 2).
  const Index lo = std::max({Index{0}, k - (m - 1), (k - r + 1) / 2});
  const Index hi = std::min({n - 1, k, (k + r) / 2});
  return {lo, hi};
}

// One pair, `count` channels summed per cell (kSingle: exactly one channel).
// Anti-diagonal k is stored by row i at position i - lo_k + 1 of its buffer; positions
// 0 and len + 1 hold +inf so that neighbours outside the matrix or band read as +inf.
// Diagonal "-2" holds D(-1, -1) = 0 at position 0 and diagonal "-1" is all +inf.
template <DtwCost kCost, bool kSingle, bool kAbandon>
double diagonalKernel(const KernelProblem& p) {
  const Tag d;
  const Index lanes = static_cast<Index>(hn::Lanes(d));
  const Index n = static_cast<Index>(p.n);
  const Index m = static_cast<Index>(p.m);
  const Index r = p.radius >= std::max(p.n, p.m) ? std::max(n, m) : static_cast<Index>(p.radius);
  const std::size_t count = p.count;

  // Padded copies: a as is, b reversed (so b[k - i] is contiguous in i), each channel
  // followed by `lanes` zeros that the last, partial vector of a diagonal may read.
  const Index a_stride = n + lanes;
  const Index b_stride = m + lanes;
  std::vector<double> a_pad(count * a_stride, 0.0);
  std::vector<double> b_rev(count * b_stride, 0.0);
  for (std::size_t c = 0; c < count; ++c) {
    std::copy(p.a[c], p.a[c] + n, a_pad.begin() + c * a_stride);
    std::reverse_copy(p.b[c], p.b[c] + m, b_rev.begin() + c * b_stride);
  }

  // Three rotating anti-diagonal buffers, long enough for the longest diagonal, the two
  // sentinels and a partial vector's overrun.
  const Index max_len = std::min({n, m, r + 1});
  const std::size_t buf_len = static_cast<std::size_t>(max_len + 2 * lanes + 4);
  std::vector<double> buffers(3 * buf_len, kInf);
  double* prev2 = buffers.data();
  double* prev1 = prev2 + buf_len;
  double* cur = prev1 + buf_len;
  prev2[0] = 0.0;  // D(-1, -1)
  Index base2 = 0;
  Index base1 = 0;
  double prev_min = kInf;  // smallest cell of diagonal k - 1 (early abandoning)
  const Vd inf = hn::Set(d, kInf);

  for (Index k = 0; k <= n + m - 2; ++k) {
    const DiagonalRange range = diagonalRange(k, n, m, r);
    double diag_min = kInf;
    cur[0] = kInf;
    if (range.lo <= range.hi) {
      // Row i reads up = (i-1, j) and left = (i, j-1) from diagonal k - 1, diag =
      // (i-1, j-1) from diagonal k - 2; pointers are at i = lo.
      const Index len = range.hi - range.lo + 1;
      const double* up = prev1 + (range.lo - base1);
      const double* left = up + 1;
      const double* diag = prev2 + (range.lo - base2);
      double* out = cur + 1;
      const double* a0 = a_pad.data() + range.lo;
      const double* b0 = b_rev.data() + (m - 1 - k + range.lo);
      Vd vmin = inf;
      for (Index t = 0; t < len; t += lanes) {
        Vd cost = localCost<kCost>(hn::LoadU(d, a0 + t), hn::LoadU(d, b0 + t));
        if constexpr (!kSingle) {
          for (std::size_t c = 1; c < count; ++c) {
            cost = hn::Add(cost, localCost<kCost>(hn::LoadU(d, a0 + c * a_stride + t),
                                                  hn::LoadU(d, b0 + c * b_stride + t)));
          }
        }
        const Vd best =
            hn::Min(hn::Min(hn::LoadU(d, up + t), hn::LoadU(d, left + t)), hn::LoadU(d, diag + t));
        const Vd value = hn::Add(cost, best);
        hn::StoreU(value, d, out + t);
        if constexpr (kAbandon) {
          const Vd valid =
              t + lanes <= len
                  ? value
                  : hn::IfThenElse(hn::FirstN(d, static_cast<std::size_t>(len - t)), value, inf);
          vmin = hn::Min(vmin, valid);
        }
      }
      cur[len + 1] = kInf;
      if constexpr (kAbandon) diag_min = hn::GetLane(hn::MinOfLanes(d, vmin));
    } else {
      cur[1] = kInf;
    }

    // Every path crosses diagonal k - 1 or k; costs are >= 0, so if both lie wholly above
    // the bound, so does every path.
    if constexpr (kAbandon) {
      if (diag_min > p.bound && prev_min > p.bound) return kInf;
      prev_min = diag_min;
    }
    double* const recycled = prev2;
    prev2 = prev1;
    prev1 = cur;
    cur = recycled;
    base2 = base1;
    base1 = range.lo;
  }
  // The last diagonal is the single cell (n-1, m-1) at position 1.
  const double result = prev1[(n - 1) - base1 + 1];
  return result > p.bound ? kInf : result;
}

// One cell D(i, j) of one vector of pairs, inside a strip of rows: `up` is D(i-1, j), `diag`
// D(i-1, j-1), and `left` (in L1) holds the row's D(i, j-1), which the cell replaces; `diag`
// becomes that old value, the next row's diagonal. Returns the cell: the next row's `up`.
template <DtwCost kCost>
HWY_INLINE Vd stripCell(Tag d, Vd a_i, Vd b_j, Vd up, Vd& diag, double* left) {
  const Vd old = hn::LoadU(d, left);
  const Vd value = hn::Add(localCost<kCost>(a_i, b_j), hn::Min(hn::Min(up, diag), old));
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

// Many univariate pairs of equal lengths; lane s of the block holds pair block + s.
// Series are interleaved (element i of every pair of the block side by side). D is computed
// in strips of kStripRows rows, column by column: each column's b_j is loaded once for the
// strip, the strip's rows keep their D(i, j-1) in a small buffer in L1, and the full-width
// row of D (the strip's last row, the next strip's top) is read and written once per strip,
// not once per row: the block stays within the core's own caches. Four vectors of pairs
// advance together, so the chain down a column overlaps four ways. Every cell is the same
// expression as the other kernels', so the costs do not depend on the order.
template <DtwCost kCost, bool kAbandon>
void batchKernel(const KernelProblem& p, double* out) {
  const Tag d;
  const std::size_t lanes = hn::Lanes(d);
  const std::size_t width = kBatchGroups * lanes;
  const std::size_t n = p.n;
  const std::size_t m = p.m;
  const std::size_t r = std::min(p.radius, std::max(n, m));
  std::vector<double> a_int(n * width);
  std::vector<double> b_int(m * width);
  std::vector<double> row(m * width);
  std::vector<double> left(kStripRows * width);
  const Vd inf = hn::Set(d, kInf);

  for (std::size_t block = 0; block < p.count; block += width) {
    // Interleave the block's pairs; lanes past the last pair repeat it (results dropped).
    for (std::size_t s = 0; s < width; ++s) {
      const std::size_t pair = std::min(block + s, p.count - 1);
      for (std::size_t i = 0; i < n; ++i) a_int[i * width + s] = p.a[pair][i];
      for (std::size_t j = 0; j < m; ++j) b_int[j * width + s] = p.b[pair][j];
    }
    std::fill(row.begin(), row.end(), kInf);

    bool abandoned = false;
    for (std::size_t i0 = 0; i0 < n && !abandoned; i0 += kStripRows) {
      const std::size_t rows = std::min(kStripRows, n - i0);
      const std::size_t i_last = i0 + rows - 1;
      // The strip's columns: from its first row's band to its last row's. Left of them every
      // row's D(i, j-1) is outside the band: +inf.
      const std::size_t j_first = i0 > r ? i0 - r : 0;
      const std::size_t j_last = std::min(m - 1, i_last + r);
      std::fill(left.begin(), left.begin() + static_cast<std::ptrdiff_t>(rows * width), kInf);
      // D(i0-1, j_first-1), the first row's diagonal: D(-1, -1) = 0 on row 0, +inf left of
      // column 0 otherwise.
      Vd top0 = i0 == 0 ? hn::Zero(d) : inf;
      Vd top1 = top0, top2 = top0, top3 = top0;
      if (j_first > 0) {
        const double* c = row.data() + (j_first - 1) * width;
        top0 = hn::LoadU(d, c);
        top1 = hn::LoadU(d, c + lanes);
        top2 = hn::LoadU(d, c + 2 * lanes);
        top3 = hn::LoadU(d, c + 3 * lanes);
      }
      Vd min0 = inf, min1 = inf, min2 = inf, min3 = inf;
      for (std::size_t j = j_first; j <= j_last; ++j) {
        const double* b_j = b_int.data() + j * width;
        const Vd b0 = hn::LoadU(d, b_j);
        const Vd b1 = hn::LoadU(d, b_j + lanes);
        const Vd b2 = hn::LoadU(d, b_j + 2 * lanes);
        const Vd b3 = hn::LoadU(d, b_j + 3 * lanes);
        // Down the column: up starts as D(i0-1, j) from the row above the strip.
        double* cell = row.data() + j * width;
        Vd up0 = hn::LoadU(d, cell);
        Vd up1 = hn::LoadU(d, cell + lanes);
        Vd up2 = hn::LoadU(d, cell + 2 * lanes);
        Vd up3 = hn::LoadU(d, cell + 3 * lanes);
        Vd diag0 = top0, diag1 = top1, diag2 = top2, diag3 = top3;
        top0 = up0;
        top1 = up1;
        top2 = up2;
        top3 = up3;
        for (std::size_t k = 0; k < rows; ++k) {
          const std::size_t i = i0 + k;
          double* l = left.data() + k * width;
          if (j + r >= i && j <= i + r) {  // |i - j| <= r
            const double* a_i = a_int.data() + i * width;
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
      }
      // Every path crosses the strip's last row: stop when all lanes' rows exceed the bound.
      if constexpr (kAbandon) {
        const Vd all = hn::Min(hn::Min(min0, min1), hn::Min(min2, min3));
        abandoned = hn::GetLane(hn::MinOfLanes(d, all)) > p.bound;
      }
    }

    const double* last = row.data() + (m - 1) * width;
    for (std::size_t s = 0; s < width && block + s < p.count; ++s) {
      out[block + s] = abandoned || last[s] > p.bound ? kInf : last[s];
    }
  }
}

// Per-target entry points: choose the template instance for the options.
double diagonalDtwTarget(const KernelProblem& p) {
  const bool abandon = p.bound < kInf;
  const bool single = p.count == 1;
  if (p.cost == DtwCost::kAbsolute) {
    if (single) {
      return abandon ? diagonalKernel<DtwCost::kAbsolute, true, true>(p)
                     : diagonalKernel<DtwCost::kAbsolute, true, false>(p);
    }
    return abandon ? diagonalKernel<DtwCost::kAbsolute, false, true>(p)
                   : diagonalKernel<DtwCost::kAbsolute, false, false>(p);
  }
  if (single) {
    return abandon ? diagonalKernel<DtwCost::kSquared, true, true>(p)
                   : diagonalKernel<DtwCost::kSquared, true, false>(p);
  }
  return abandon ? diagonalKernel<DtwCost::kSquared, false, true>(p)
                 : diagonalKernel<DtwCost::kSquared, false, false>(p);
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

HWY_EXPORT(diagonalDtwTarget);
HWY_EXPORT(batchDtwTarget);
HWY_EXPORT(batchWidthTarget);
HWY_EXPORT(targetNameTarget);

double diagonalDtw(const KernelProblem& problem) {
  return HWY_DYNAMIC_DISPATCH(diagonalDtwTarget)(problem);
}

void batchDtw(const KernelProblem& problem, double* out) {
  HWY_DYNAMIC_DISPATCH(batchDtwTarget)(problem, out);
}

std::size_t batchWidth() { return HWY_DYNAMIC_DISPATCH(batchWidthTarget)(); }

const char* simdTargetName() { return HWY_DYNAMIC_DISPATCH(targetNameTarget)(); }

}  // namespace hattr::analysis::detail
#endif  // HWY_ONCE
