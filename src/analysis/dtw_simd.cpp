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
//  - batchKernel: many pairs of equal lengths. SIMD lanes are different pairs, each lane
//    runs the plain row recurrence; four vectors of pairs are interleaved to hide the
//    latency of the sequential D(i, j-1) dependency.

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

// One step of the row recurrence for one vector of pairs at column j.
template <DtwCost kCost, bool kAbandon>
HWY_INLINE void batchStep(Tag d, Vd a_i, const double* b_j, double* cell, Vd& diag, Vd& left,
                          Vd& row_min) {
  const Vd up = hn::LoadU(d, cell);
  const Vd value =
      hn::Add(localCost<kCost>(a_i, hn::LoadU(d, b_j)), hn::Min(hn::Min(up, diag), left));
  diag = up;
  left = value;
  hn::StoreU(value, d, cell);
  if constexpr (kAbandon) row_min = hn::Min(row_min, value);
}

// Many univariate pairs of equal lengths; lane s of the block holds pair block + s.
// Series are interleaved (element i of every pair of the block side by side) and one row
// of D per lane is kept; four vectors of pairs advance together along each row.
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
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j_lo = i > r ? i - r : 0;
      const std::size_t j_hi = std::min(m - 1, i + r);
      const double* a_i = a_int.data() + i * width;
      const Vd a0 = hn::LoadU(d, a_i);
      const Vd a1 = hn::LoadU(d, a_i + lanes);
      const Vd a2 = hn::LoadU(d, a_i + 2 * lanes);
      const Vd a3 = hn::LoadU(d, a_i + 3 * lanes);
      // diag starts as D(i-1, j_lo-1): row i-1's value there, D(-1, -1) = 0 on row 0,
      // +inf left of column 0 otherwise.
      Vd diag0 = i == 0 ? hn::Zero(d) : inf;
      Vd diag1 = diag0;
      Vd diag2 = diag0;
      Vd diag3 = diag0;
      if (j_lo > 0) {
        const double* c = row.data() + (j_lo - 1) * width;
        diag0 = hn::LoadU(d, c);
        diag1 = hn::LoadU(d, c + lanes);
        diag2 = hn::LoadU(d, c + 2 * lanes);
        diag3 = hn::LoadU(d, c + 3 * lanes);
      }
      Vd left0 = inf, left1 = inf, left2 = inf, left3 = inf;
      Vd min0 = inf, min1 = inf, min2 = inf, min3 = inf;
      for (std::size_t j = j_lo; j <= j_hi; ++j) {
        const double* b_j = b_int.data() + j * width;
        double* cell = row.data() + j * width;
        batchStep<kCost, kAbandon>(d, a0, b_j, cell, diag0, left0, min0);
        batchStep<kCost, kAbandon>(d, a1, b_j + lanes, cell + lanes, diag1, left1, min1);
        batchStep<kCost, kAbandon>(d, a2, b_j + 2 * lanes, cell + 2 * lanes, diag2, left2, min2);
        batchStep<kCost, kAbandon>(d, a3, b_j + 3 * lanes, cell + 3 * lanes, diag3, left3, min3);
      }
      // Every path crosses every row: stop when all lanes' rows exceed the bound.
      if constexpr (kAbandon) {
        const Vd all = hn::Min(hn::Min(min0, min1), hn::Min(min2, min3));
        if (hn::GetLane(hn::MinOfLanes(d, all)) > p.bound) {
          abandoned = true;
          break;
        }
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
