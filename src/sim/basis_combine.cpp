// The trainee's basis combined by a few columns of weights (combineBasis), vectorized with
// Highway: foreach_target.h compiles this file once per instruction set and
// HWY_DYNAMIC_DISPATCH picks the best the CPU has at run time. Lanes are rows, so every entry
// is still its own sum over the basis functions in turn, from zero, one multiply and one add
// per function: the same bits on every target. The file is compiled with -ffp-contract=off
// (src/CMakeLists.txt), so that no compiler fuses the two into a multiply-add.
// foreach_target.h re-includes this file by the name below: src/ must be on the include path.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "sim/basis_combine.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include <cstddef>

#include "trainee_internal.hpp"

HWY_BEFORE_NAMESPACE();
namespace hattr::sim::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using Tag = hn::ScalableTag<double>;
using Vd = hn::Vec<Tag>;

// Rows [first, first + 4 vectors) of kCols columns: four vectors of sums per column, each
// function's four vectors of basis values read once for all the columns.
template <int kCols>
HWY_INLINE void combineFourVectors(Tag d, const BasisCombination& c, std::size_t first) {
  const std::size_t lanes = hn::Lanes(d);
  Vd x0 = hn::Zero(d), x1 = x0, x2 = x0, x3 = x0;
  Vd y0 = x0, y1 = x0, y2 = x0, y3 = x0;
  Vd z0 = x0, z1 = x0, z2 = x0, z3 = x0;
  for (std::size_t k = 0; k < c.functions; ++k) {
    const double* basis = c.phi + k * c.rows + first;
    const Vd b0 = hn::LoadU(d, basis), b1 = hn::LoadU(d, basis + lanes);
    const Vd b2 = hn::LoadU(d, basis + 2 * lanes), b3 = hn::LoadU(d, basis + 3 * lanes);
    const Vd wx = hn::Set(d, c.weights[0][k]);
    x0 = hn::Add(x0, hn::Mul(b0, wx));
    x1 = hn::Add(x1, hn::Mul(b1, wx));
    x2 = hn::Add(x2, hn::Mul(b2, wx));
    x3 = hn::Add(x3, hn::Mul(b3, wx));
    if constexpr (kCols >= 2) {
      const Vd wy = hn::Set(d, c.weights[1][k]);
      y0 = hn::Add(y0, hn::Mul(b0, wy));
      y1 = hn::Add(y1, hn::Mul(b1, wy));
      y2 = hn::Add(y2, hn::Mul(b2, wy));
      y3 = hn::Add(y3, hn::Mul(b3, wy));
    }
    if constexpr (kCols >= 3) {
      const Vd wz = hn::Set(d, c.weights[2][k]);
      z0 = hn::Add(z0, hn::Mul(b0, wz));
      z1 = hn::Add(z1, hn::Mul(b1, wz));
      z2 = hn::Add(z2, hn::Mul(b2, wz));
      z3 = hn::Add(z3, hn::Mul(b3, wz));
    }
  }
  const auto store = [&](double* out, Vd s0, Vd s1, Vd s2, Vd s3) {
    hn::StoreU(s0, d, out + first);
    hn::StoreU(s1, d, out + first + lanes);
    hn::StoreU(s2, d, out + first + 2 * lanes);
    hn::StoreU(s3, d, out + first + 3 * lanes);
  };
  store(c.out[0], x0, x1, x2, x3);
  if constexpr (kCols >= 2) store(c.out[1], y0, y1, y2, y3);
  if constexpr (kCols >= 3) store(c.out[2], z0, z1, z2, z3);
}

// One row, the same sums one lane wide.
HWY_INLINE void combineRow(const BasisCombination& c, std::size_t row) {
  for (std::size_t j = 0; j < c.columns; ++j) {
    double sum = 0.0;
    for (std::size_t k = 0; k < c.functions; ++k) sum += c.phi[k * c.rows + row] * c.weights[j][k];
    c.out[j][row] = sum;
  }
}

template <int kCols>
void combineAll(const BasisCombination& c) {
  const Tag d;
  const std::size_t block = 4 * hn::Lanes(d);
  std::size_t first = 0;
  for (; first + block <= c.rows; first += block) combineFourVectors<kCols>(d, c, first);
  for (; first < c.rows; ++first) combineRow(c, first);
}

void combineBasisTarget(const BasisCombination& c) {
  if (c.columns == 1) combineAll<1>(c);
  if (c.columns == 2) combineAll<2>(c);
  if (c.columns == 3) combineAll<3>(c);
}

}  // namespace HWY_NAMESPACE
}  // namespace hattr::sim::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hattr::sim::detail {

HWY_EXPORT(combineBasisTarget);

void combineBasisColumns(const BasisCombination& combination) {
  HWY_DYNAMIC_DISPATCH(combineBasisTarget)(combination);
}

}  // namespace hattr::sim::detail
#endif
