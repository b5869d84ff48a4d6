// The compact sample encoding's predictions (sample_codec_predictors_internal.hpp). Compiled with
// -ffp-contract=off (src/CMakeLists.txt): the predictions must round the same in every build.

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <type_traits>
#include <utility>
#include <vector>

#include "sample_codec_internal.hpp"
#include "sample_codec_predictors_internal.hpp"

namespace hattr::io::detail {
namespace {

// ---- Predictions: doubles (lossless) and whole steps (declared resolution) ----------------

/// A difference of bit patterns as an unsigned number, small ones of either sign small; and back.
std::uint64_t zigzag(std::uint64_t difference) { return (difference << 1) ^ (0 - (difference >> 63)); }
std::uint64_t unzigzag(std::uint64_t z) { return (z >> 1) ^ (0 - (z & 1)); }

/// The prediction of value `i` of a column from the values before it (fewer at its start).
template <class D>
typename D::Value predict(Predictor p, const typename D::Value* column, std::size_t i) {
  if (i == 0) return 0;
  if (p == Predictor::kPrevious || i == 1) return column[i - 1];
  if (p == Predictor::kLine || i == 2) return D::line(column[i - 1], column[i - 2]);
  return D::quadratic(column[i - 1], column[i - 2], column[i - 3]);
}

/// How many values before it an option needs to predict a value (hsc2).
constexpr std::size_t historyOf(Option o) {
  constexpr std::size_t kHistory[] = {1, 2, 3, 4, 7, 11, 1, 5};
  static_assert(std::size(kHistory) == kKinematicOptions);
  return kHistory[static_cast<std::size_t>(o)];
}

/// The prediction of value `i` (i >= historyOf(O)) by one of a chosen channel's options, from
/// the values before it and the quadratic's and kinematic prediction at a sample (`quadratic(j)`,
/// `kinematic(j)`: made on the spot by the decoder, looked up by the encoder).
template <Option O, class Quadratic, class Kinematic>
double predictBy(const double* v, std::size_t i, const Quadratic& quadratic, const Kinematic& kinematic) {
  using D = Doubles;
  if constexpr (O == Option::kPrevious) return v[i - 1];
  if constexpr (O == Option::kLine) return D::line(v[i - 1], v[i - 2]);
  if constexpr (O == Option::kQuadratic) return quadratic(i);
  if constexpr (O == Option::kCubic) return D::cubic(v[i - 1], v[i - 2], v[i - 3], v[i - 4]);
  if constexpr (O == Option::kPeriodic4) return D::plusMiss(quadratic(i), v[i - 4], quadratic(i - 4));
  if constexpr (O == Option::kPeriodic8) return D::plusMiss(quadratic(i), v[i - 8], quadratic(i - 8));
  if constexpr (O == Option::kKinematic) return kinematic(i);
  if constexpr (O == Option::kKinematicPeriodic4) return D::plusMiss(kinematic(i), v[i - 4], kinematic(i - 4));
}

/// Calls `body` with option `o` as a compile-time constant, so that each option's loop is
/// compiled without a branch per value.
template <class Body>
void withOption(Option o, Body&& body) {
  switch (o) {
    case Option::kPrevious: return body(std::integral_constant<Option, Option::kPrevious>{});
    case Option::kLine: return body(std::integral_constant<Option, Option::kLine>{});
    case Option::kQuadratic: return body(std::integral_constant<Option, Option::kQuadratic>{});
    case Option::kCubic: return body(std::integral_constant<Option, Option::kCubic>{});
    case Option::kPeriodic4: return body(std::integral_constant<Option, Option::kPeriodic4>{});
    case Option::kPeriodic8: return body(std::integral_constant<Option, Option::kPeriodic8>{});
    case Option::kKinematic: return body(std::integral_constant<Option, Option::kKinematic>{});
    case Option::kKinematicPeriodic4: return body(std::integral_constant<Option, Option::kKinematicPeriodic4>{});
  }
}

/// The zigzagged difference of a value's bits from its prediction's.
template <class D>
std::uint64_t residualOf(typename D::Value value, typename D::Value predicted) {
  return zigzag(D::bits(value) - D::bits(predicted));
}

/// The value back from its residual and its prediction.
template <class D>
typename D::Value valueOf(std::uint64_t residual, typename D::Value predicted) {
  return D::fromBits(unzigzag(residual) + D::bits(predicted));
}

}  // namespace

// ---- Fixed predictors ----------------------------------------------------------------------

/// A column's residuals under a fixed predictor: the zigzagged differences from the
/// predictions. `guide` and `user` are the axis's columns for kCommand.
template <class D>
void encodeColumn(Predictor p, const typename D::Value* column, const typename D::Value* guide,
                  const typename D::Value* user, std::uint64_t* out, std::size_t n) {
  if (p == Predictor::kCommand) {
    for (std::size_t i = 0; i < n; ++i) out[i] = residualOf<D>(column[i], D::command(guide[i], user[i]));
    return;
  }
  const std::size_t head = std::min<std::size_t>(n, 3);
  for (std::size_t i = 0; i < head; ++i) out[i] = residualOf<D>(column[i], predict<D>(p, column, i));
  // Past the first three, one predictor without branches.
  if (p == Predictor::kPrevious) {
    for (std::size_t i = head; i < n; ++i) out[i] = residualOf<D>(column[i], column[i - 1]);
  } else if (p == Predictor::kLine) {
    for (std::size_t i = head; i < n; ++i) out[i] = residualOf<D>(column[i], D::line(column[i - 1], column[i - 2]));
  } else {
    for (std::size_t i = head; i < n; ++i) {
      out[i] = residualOf<D>(column[i], D::quadratic(column[i - 1], column[i - 2], column[i - 3]));
    }
  }
}

/// The column back from its residuals under a fixed predictor, value by value (each
/// prediction needs the values before it).
template <class D>
void decodeColumn(Predictor p, const std::uint64_t* residuals, const typename D::Value* guide,
                  const typename D::Value* user, typename D::Value* column, std::size_t n) {
  if (p == Predictor::kCommand) {
    for (std::size_t i = 0; i < n; ++i) column[i] = valueOf<D>(residuals[i], D::command(guide[i], user[i]));
    return;
  }
  const std::size_t head = std::min<std::size_t>(n, 3);
  for (std::size_t i = 0; i < head; ++i) column[i] = valueOf<D>(residuals[i], predict<D>(p, column, i));
  if (p == Predictor::kPrevious) {
    for (std::size_t i = head; i < n; ++i) column[i] = valueOf<D>(residuals[i], column[i - 1]);
  } else if (p == Predictor::kLine) {
    for (std::size_t i = head; i < n; ++i) column[i] = valueOf<D>(residuals[i], D::line(column[i - 1], column[i - 2]));
  } else {
    for (std::size_t i = head; i < n; ++i) {
      column[i] = valueOf<D>(residuals[i], D::quadratic(column[i - 1], column[i - 2], column[i - 3]));
    }
  }
}

// The two kinds of column the revisions encode and decode: doubles and whole steps.
template void encodeColumn<Doubles>(Predictor, const double*, const double*, const double*, std::uint64_t*, std::size_t);
template void encodeColumn<Steps>(Predictor, const std::uint64_t*, const std::uint64_t*, const std::uint64_t*,
                                  std::uint64_t*, std::size_t);
template void decodeColumn<Doubles>(Predictor, const std::uint64_t*, const double*, const double*, double*, std::size_t);
template void decodeColumn<Steps>(Predictor, const std::uint64_t*, const std::uint64_t*, const std::uint64_t*,
                                  std::uint64_t*, std::size_t);

// ---- Predictions chosen per block (hsc2) ---------------------------------------------------

/// A chosen channel's residuals: for each block of kBlock samples, the option whose residuals
/// take the fewest significant bits (the lowest-numbered one on a tie), written to `choices`.
/// Near the column's start, where an option lacks the values it needs, the quadratic's start
/// (predict) stands in. The quadratic and kinematic predictions, which several options share,
/// are made once: the same operations on the same values as the decoder's, so the same bits.
void encodeChosenColumn(std::size_t options, const double* v, const Kinematics& k, std::uint64_t* out,
                        std::uint8_t* choices, std::size_t n) {
  using D = Doubles;
  std::vector<double> quadratic(n, 0.0), kinematic(options > kOptions ? n : 0, 0.0);
  for (std::size_t i = 3; i < n; ++i) quadratic[i] = D::quadratic(v[i - 1], v[i - 2], v[i - 3]);
  for (std::size_t i = 1; i < kinematic.size(); ++i) kinematic[i] = k.at(v, i);
  const auto quadratic_at = [&](std::size_t j) { return quadratic[j]; };
  const auto kinematic_at = [&](std::size_t j) { return kinematic[j]; };
  // The residuals of samples [from, to) under option O, to `use(i, residual)`.
  const auto residuals = [&](auto option, std::size_t from, std::size_t to, auto&& use) {
    constexpr Option kO = decltype(option)::value;
    const std::size_t start = std::clamp(historyOf(kO), from, to);
    for (std::size_t i = from; i < start; ++i) use(i, residualOf<D>(v[i], predict<D>(Predictor::kQuadratic, v, i)));
    for (std::size_t i = start; i < to; ++i) use(i, residualOf<D>(v[i], predictBy<kO>(v, i, quadratic_at, kinematic_at)));
  };

  // Each option's bits per block, then each block's choice and residuals.
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::uint64_t> bits(options * blocks, 0);
  for (std::size_t o = 0; o < options; ++o) {
    withOption(static_cast<Option>(o), [&](auto option) {
      for (std::size_t b = 0; b < blocks; ++b) {
        std::uint64_t sum = 0;
        residuals(option, b * kBlock, std::min(n, (b + 1) * kBlock),
                  [&sum](std::size_t, std::uint64_t r) { sum += static_cast<std::uint64_t>(std::bit_width(r)); });
        bits[o * blocks + b] = sum;
      }
    });
  }
  for (std::size_t b = 0; b < blocks; ++b) {
    std::size_t best = 0;
    for (std::size_t o = 1; o < options; ++o) {
      if (bits[o * blocks + b] < bits[best * blocks + b]) best = o;
    }
    choices[b] = static_cast<std::uint8_t>(best);
    withOption(static_cast<Option>(best), [&](auto option) {
      residuals(option, b * kBlock, std::min(n, (b + 1) * kBlock), [&](std::size_t i, std::uint64_t r) { out[i] = r; });
    });
  }
}

/// A chosen channel's column back from its residuals, block by block, each with the prediction
/// its choice names (the encoder's, made here from the values already decoded).
void decodeChosenColumn(const std::uint8_t* choices, const std::uint64_t* residuals, const Kinematics& k, double* column,
                        std::size_t n) {
  using D = Doubles;
  const auto quadratic_at = [column](std::size_t j) { return D::quadratic(column[j - 1], column[j - 2], column[j - 3]); };
  const auto kinematic_at = [column, &k](std::size_t j) { return k.at(column, j); };
  for (std::size_t from = 0, b = 0; from < n; from += kBlock, ++b) {
    const std::size_t to = std::min(n, from + kBlock);
    withOption(static_cast<Option>(choices[b]), [&](auto option) {
      constexpr Option kO = decltype(option)::value;
      const std::size_t start = std::clamp(historyOf(kO), from, to);
      for (std::size_t i = from; i < start; ++i) {
        column[i] = valueOf<D>(residuals[i], predict<D>(Predictor::kQuadratic, column, i));
      }
      for (std::size_t i = start; i < to; ++i) {
        column[i] = valueOf<D>(residuals[i], predictBy<kO>(column, i, quadratic_at, kinematic_at));
      }
    });
  }
}

/// a and b of a position's kinematic prediction, fitted to the trial: Δp ≈ Δt·(a·v_i + b·v_(i-1)),
/// by least squares, then twice more reweighted towards the least absolute misses (the stored bits grow
/// with the log of the miss, so a few large misses must not steer the fit). The fit only
/// decides how small the residuals are: the decoder uses the stored a and b.
std::pair<double, double> fitKinematics(const double* position, const double* velocity, const double* time, std::size_t n) {
  constexpr std::pair<double, double> kTrapezoid = {0.5, 0.5};
  if (n < 3) return kTrapezoid;
  std::vector<double> weight(n, 1.0);
  double mean_step = 0.0;
  for (std::size_t i = 1; i < n; ++i) mean_step += std::abs(position[i] - position[i - 1]) / static_cast<double>(n - 1);
  std::pair<double, double> fit = kTrapezoid;
  for (int round = 0; round < 3; ++round) {
    double s11 = 0.0, s12 = 0.0, s22 = 0.0, r1 = 0.0, r2 = 0.0;
    for (std::size_t i = 1; i < n; ++i) {
      const double dt = time[i] - time[i - 1];
      const double x1 = dt * velocity[i], x2 = dt * velocity[i - 1], y = position[i] - position[i - 1];
      s11 += weight[i] * x1 * x1;
      s12 += weight[i] * x1 * x2;
      s22 += weight[i] * x2 * x2;
      r1 += weight[i] * x1 * y;
      r2 += weight[i] * x2 * y;
    }
    const double det = s11 * s22 - s12 * s12;
    if (!(std::isfinite(det) && det > 1e-12 * s11 * s22)) return fit;
    const std::pair<double, double> next = {(r1 * s22 - r2 * s12) / det, (r2 * s11 - r1 * s12) / det};
    if (!std::isfinite(next.first) || !std::isfinite(next.second)) return fit;
    fit = next;
    if (round == 2) break;
    for (std::size_t i = 1; i < n; ++i) {
      const double dt = time[i] - time[i - 1];
      const double miss = position[i] - position[i - 1] - dt * (fit.first * velocity[i] + fit.second * velocity[i - 1]);
      weight[i] = 1.0 / (std::abs(miss) + 1e-9 * mean_step + DBL_MIN);
    }
  }
  return fit;
}

}  // namespace hattr::io::detail
