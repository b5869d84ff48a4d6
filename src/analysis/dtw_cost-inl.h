// The local cost of two vectors of samples, per instruction set, for the DTW kernels
// (dtw_simd.cpp, dtw_pair_simd.cpp): Highway's per-target header, included after highway.h
// by each file that foreach_target.h compiles once per instruction set.

#if defined(HATTR_ANALYSIS_DTW_COST_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef HATTR_ANALYSIS_DTW_COST_INL_H_
#undef HATTR_ANALYSIS_DTW_COST_INL_H_
#else
#define HATTR_ANALYSIS_DTW_COST_INL_H_
#endif

#include <hwy/highway.h>

#include <limits>

#include "dtw_internal.hpp"

HWY_BEFORE_NAMESPACE();
namespace hattr::analysis::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using Tag = hn::ScalableTag<double>;
using Vd = hn::Vec<Tag>;
using Index = std::ptrdiff_t;

constexpr double kInf = std::numeric_limits<double>::infinity();

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

}  // namespace HWY_NAMESPACE
}  // namespace hattr::analysis::detail
HWY_AFTER_NAMESPACE();

#endif  // HATTR_ANALYSIS_DTW_COST_INL_H_
