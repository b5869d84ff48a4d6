// The vectorized DTW kernel of one pair (Highway), dispatched at run time like the batch kernel
// of dtw_simd.cpp. The cells of an anti-diagonal k = i + j depend only on the two previous
// anti-diagonals, so a whole anti-diagonal is one stream of independent SIMD operations: three
// anti-diagonal buffers, O(band) memory. Diagonals longer than a stripe of rows (1024) are
// computed a stripe at a time, so that the buffers stay in L1. This file re-includes itself by
// the name below: src/ must be on the include path of this translation unit.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "analysis/dtw_pair_simd.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <cstddef>
#include <utility>
#include <vector>

#include "analysis/dtw_cost-inl.h"
#include "dtw_internal.hpp"

HWY_BEFORE_NAMESPACE();
namespace hattr::analysis::detail {
namespace HWY_NAMESPACE {

// Rows per stripe of stripedDiagonalKernel: its three diagonal buffers (3 × 8 KB) stay in L1.
constexpr Index kPairStripeRows = 1024;

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

// Padded copies for diagonalKernel: a as is, b reversed (so b[k - i] is contiguous in i), each
// channel followed by `lanes` zeros that the last, partial vector of a diagonal may read.
inline std::pair<std::vector<double>, std::vector<double>> padForDiagonals(const KernelProblem& p, Index lanes) {
  const Index n = static_cast<Index>(p.n);
  const Index m = static_cast<Index>(p.m);
  const Index a_stride = n + lanes;
  const Index b_stride = m + lanes;
  std::vector<double> a_pad(p.count * a_stride, 0.0);
  std::vector<double> b_rev(p.count * b_stride, 0.0);
  for (std::size_t c = 0; c < p.count; ++c) {
    std::copy(p.a[c], p.a[c] + n, a_pad.begin() + c * a_stride);
    std::reverse_copy(p.b[c], p.b[c] + m, b_rev.begin() + c * b_stride);
  }
  return {std::move(a_pad), std::move(b_rev)};
}

// The local cost of one vector of a diagonal's cells (diagonalKernel): `count` channels
// summed, each `a_stride` (`b_stride`) after the last (kSingle: exactly one channel).
template <DtwCost kCost, bool kSingle>
HWY_INLINE Vd diagonalCost(Tag d, const double* a, const double* b, std::size_t count, Index a_stride, Index b_stride) {
  Vd cost = localCost<kCost>(hn::LoadU(d, a), hn::LoadU(d, b));
  if constexpr (!kSingle) {
    for (std::size_t c = 1; c < count; ++c) {
      cost = hn::Add(cost, localCost<kCost>(hn::LoadU(d, a + c * a_stride), hn::LoadU(d, b + c * b_stride)));
    }
  }
  return cost;
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

  const Index a_stride = n + lanes;
  const Index b_stride = m + lanes;
  const auto [a_pad, b_rev] = padForDiagonals(p, lanes);

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
        const Vd cost = diagonalCost<kCost, kSingle>(d, a0 + t, b0 + t, count, a_stride, b_stride);
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

// One stripe of rows [i0, i1] of diagonalKernel's matrix, anti-diagonal by anti-diagonal as
// there, the row above read from `above` (above[j + 1] = D(i0 - 1, j), above[0] = D(i0 - 1, -1))
// and the stripe's last row written to `below` (the same layout, +inf where not computed). The
// buffers are the caller's, each at least min(stripe, m, r + 1) + 2 lanes + 4 long. Returns the
// smallest cell of the last row (early abandoning: every path crosses it).
template <DtwCost kCost, bool kSingle>
double diagonalStripe(Tag d, const KernelProblem& p, const double* a_pad, const double* b_rev, Index i0, Index i1,
                      Index r, const double* above, double* below, double* buffers, std::size_t buf_len) {
  const Index lanes = static_cast<Index>(hn::Lanes(d));
  const Index n = static_cast<Index>(p.n);
  const Index m = static_cast<Index>(p.m);
  const Index a_stride = n + lanes;
  const Index b_stride = m + lanes;
  double* prev2 = buffers;
  double* prev1 = prev2 + buf_len;
  double* cur = prev1 + buf_len;
  std::fill(buffers, buffers + 3 * buf_len, kInf);
  std::fill(below, below + m + 1, kInf);
  // The diagonals before the stripe's first: empty here, their row i0 - 1 from `above`.
  Index base2 = i0;
  Index base1 = i0;
  for (Index k = i0; k <= i1 + m - 1; ++k) {
    const DiagonalRange whole = diagonalRange(k, n, m, r);
    const Index lo = std::max(whole.lo, i0);
    const Index hi = std::min(whole.hi, i1);
    cur[0] = kInf;
    if (lo <= hi) {
      // Row i0's up and diag lie in the row above the stripe: put them where row i0 - 1 would be.
      if (lo == i0) {
        prev1[i0 - base1] = above[k - i0 + 1];  // D(i0 - 1, k - i0), on diagonal k - 1
        prev2[i0 - base2] = above[k - i0];      // D(i0 - 1, k - i0 - 1), on diagonal k - 2
      }
      const Index len = hi - lo + 1;
      const double* up = prev1 + (lo - base1);
      const double* left = up + 1;
      const double* diag = prev2 + (lo - base2);
      double* out = cur + 1;
      const double* a0 = a_pad + lo;
      const double* b0 = b_rev + (m - 1 - k + lo);
      for (Index t = 0; t < len; t += lanes) {
        const Vd cost = diagonalCost<kCost, kSingle>(d, a0 + t, b0 + t, p.count, a_stride, b_stride);
        const Vd best = hn::Min(hn::Min(hn::LoadU(d, up + t), hn::LoadU(d, left + t)), hn::LoadU(d, diag + t));
        hn::StoreU(hn::Add(cost, best), d, out + t);
      }
      cur[len + 1] = kInf;
      if (hi == i1) below[k - i1 + 1] = out[i1 - lo];
    } else {
      cur[1] = kInf;
    }
    double* const recycled = prev2;
    prev2 = prev1;
    prev1 = cur;
    cur = recycled;
    base2 = base1;
    base1 = lo;
  }
  return *std::min_element(below + 1, below + m + 1);
}

// diagonalKernel for long series: stripes of kPairStripeRows rows, one after the other, so
// that a diagonal's buffers stay in L1 (past about 2 000 cells a diagonal they did not: the
// rate halved). Every cell is the same expression, so the cost is the same to the bit.
template <DtwCost kCost, bool kSingle, bool kAbandon>
double stripedDiagonalKernel(const KernelProblem& p) {
  const Tag d;
  const Index lanes = static_cast<Index>(hn::Lanes(d));
  const Index n = static_cast<Index>(p.n);
  const Index m = static_cast<Index>(p.m);
  const Index r = p.radius >= std::max(p.n, p.m) ? std::max(n, m) : static_cast<Index>(p.radius);
  const auto [a_pad, b_rev] = padForDiagonals(p, lanes);
  const std::size_t buf_len = static_cast<std::size_t>(std::min({kPairStripeRows, m, r + 1}) + 2 * lanes + 4);
  std::vector<double> buffers(3 * buf_len);
  std::vector<double> above(static_cast<std::size_t>(m + 1), kInf);
  std::vector<double> below(static_cast<std::size_t>(m + 1), kInf);
  above[0] = 0.0;  // D(-1, -1)
  for (Index i0 = 0; i0 < n; i0 += kPairStripeRows) {
    const Index i1 = std::min(n - 1, i0 + kPairStripeRows - 1);
    const double row_min = diagonalStripe<kCost, kSingle>(d, p, a_pad.data(), b_rev.data(), i0, i1, r, above.data(),
                                                          below.data(), buffers.data(), buf_len);
    if constexpr (kAbandon) {
      if (row_min > p.bound) return kInf;
    }
    std::swap(above, below);
  }
  const double result = above[static_cast<std::size_t>(m)];
  return result > p.bound ? kInf : result;
}

// One pair: diagonals longer than a stripe of rows a stripe at a time (their buffers in L1),
// others whole.
template <DtwCost kCost, bool kSingle, bool kAbandon>
double pairKernel(const KernelProblem& p) {
  const std::size_t longest_diagonal = std::min({p.n, p.m, std::min(p.radius, std::max(p.n, p.m)) + 1});
  if (longest_diagonal > static_cast<std::size_t>(kPairStripeRows)) return stripedDiagonalKernel<kCost, kSingle, kAbandon>(p);
  return diagonalKernel<kCost, kSingle, kAbandon>(p);
}

// The per-target entry point: the template instance for the options.
double diagonalDtwTarget(const KernelProblem& p) {
  const bool abandon = p.bound < kInf;
  const bool single = p.count == 1;
  if (p.cost == DtwCost::kAbsolute) {
    if (single) {
      return abandon ? pairKernel<DtwCost::kAbsolute, true, true>(p)
                     : pairKernel<DtwCost::kAbsolute, true, false>(p);
    }
    return abandon ? pairKernel<DtwCost::kAbsolute, false, true>(p)
                   : pairKernel<DtwCost::kAbsolute, false, false>(p);
  }
  if (single) {
    return abandon ? pairKernel<DtwCost::kSquared, true, true>(p)
                   : pairKernel<DtwCost::kSquared, true, false>(p);
  }
  return abandon ? pairKernel<DtwCost::kSquared, false, true>(p)
                 : pairKernel<DtwCost::kSquared, false, false>(p);
}

}  // namespace HWY_NAMESPACE
}  // namespace hattr::analysis::detail
HWY_AFTER_NAMESPACE();

// Once, after all targets: the dispatch table and the function dtw.cpp calls.
#if HWY_ONCE
namespace hattr::analysis::detail {

HWY_EXPORT(diagonalDtwTarget);

double diagonalDtw(const KernelProblem& problem) {
  return HWY_DYNAMIC_DISPATCH(diagonalDtwTarget)(problem);
}

}  // namespace hattr::analysis::detail
#endif  // HWY_ONCE
