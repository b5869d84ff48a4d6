// Vectorized lower bounds of the DTW cost (Highway), dispatched at run time like the DTW
// kernels of dtw_simd.cpp: LB_Keogh of one candidate, and the segment-mean bound of many
// candidates at once (dtw.hpp). This file re-includes itself by the name below: src/ must be on
// the include path of this translation unit.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "analysis/dtw_bounds_simd.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include <algorithm>
#include <cstddef>

#include "dtw_internal.hpp"

HWY_BEFORE_NAMESPACE();
namespace hattr::analysis::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using Tag = hn::ScalableTag<double>;
using Vd = hn::Vec<Tag>;

// How far x lies outside [lo, hi], lane by lane (0 inside).
HWY_INLINE Vd gapOutside(Vd x, Vd lo, Vd hi) {
  const Vd zero = hn::Zero(Tag());
  return hn::Add(hn::Max(hn::Sub(x, hi), zero), hn::Max(hn::Sub(lo, x), zero));
}

// LB_Keogh: Σ gap (squared when asked) over blocks of kLbBlock values, the sum checked
// against the bound after each block; the values past the last whole vector one by one.
constexpr std::size_t kLbBlock = 16;

template <bool kSquared>
double lbKeoghKernel(const LbProblem& p) {
  const Tag d;
  const std::size_t lanes = hn::Lanes(d);
  double total = 0.0;
  std::size_t i = 0;
  while (i < p.n) {
    const std::size_t block_end = std::min(p.n, i + std::max(kLbBlock, lanes));
    Vd sum = hn::Zero(d);
    for (; i + lanes <= block_end; i += lanes) {
      const Vd g = gapOutside(hn::LoadU(d, p.candidate + i), hn::LoadU(d, p.lower + i), hn::LoadU(d, p.upper + i));
      sum = kSquared ? hn::MulAdd(g, g, sum) : hn::Add(sum, g);
    }
    total += hn::GetLane(hn::SumOfLanes(d, sum));
    for (; i < block_end; ++i) {
      const double g = std::max(p.candidate[i] - p.upper[i], 0.0) + std::max(p.lower[i] - p.candidate[i], 0.0);
      total += kSquared ? g * g : g;
    }
    if (total > p.abandon_above) return total;
  }
  return total;
}

double lbKeoghTarget(const LbProblem& p) { return p.squared ? lbKeoghKernel<true>(p) : lbKeoghKernel<false>(p); }

// Segment-mean bounds of `count` candidates, `stride` means each: Σ width · gap(mean).
void segmentBoundsTarget(const double* means, std::size_t count, const SegmentEnvelopeView& e, double* out) {
  const Tag d;
  const std::size_t lanes = hn::Lanes(d);
  const std::size_t stride = e.size;
  for (std::size_t c = 0; c < count; ++c) {
    const double* m = means + c * stride;
    Vd sum = hn::Zero(d);
    std::size_t s = 0;
    for (; s + lanes <= stride; s += lanes) {
      const Vd g = gapOutside(hn::LoadU(d, m + s), hn::LoadU(d, e.lower + s), hn::LoadU(d, e.upper + s));
      sum = hn::MulAdd(hn::LoadU(d, e.width + s), g, sum);
    }
    double total = hn::GetLane(hn::SumOfLanes(d, sum));
    for (; s < stride; ++s) {
      total += e.width[s] * (std::max(m[s] - e.upper[s], 0.0) + std::max(e.lower[s] - m[s], 0.0));
    }
    out[c] = total;
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace hattr::analysis::detail
HWY_AFTER_NAMESPACE();

// Once, after all targets: the dispatch tables and the functions dtw.cpp calls.
#if HWY_ONCE
namespace hattr::analysis::detail {

HWY_EXPORT(lbKeoghTarget);
HWY_EXPORT(segmentBoundsTarget);

double lbKeoghSimd(const LbProblem& problem) { return HWY_DYNAMIC_DISPATCH(lbKeoghTarget)(problem); }

void segmentBoundsSimd(const double* means, std::size_t count, const SegmentEnvelopeView& envelope, double* out) {
  HWY_DYNAMIC_DISPATCH(segmentBoundsTarget)(means, count, envelope, out);
}

}  // namespace hattr::analysis::detail
#endif  // HWY_ONCE
