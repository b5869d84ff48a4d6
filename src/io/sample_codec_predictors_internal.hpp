#pragma once
// The compact sample encoding's predictions (sample_codec_predictors.cpp): each column's values
// predicted from the values before it, in IEEE doubles (lossless) or in wrapping 64-bit whole
// steps (declared resolution), and the zigzagged residuals they leave. Values are in each
// channel's SI unit; time in seconds.
//
// The predictions must round the same in every build: every file that does this arithmetic
// is compiled with -ffp-contract=off (src/CMakeLists.txt), and FLT_EVAL_METHOD is 0.

#include <bit>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "sample_codec_internal.hpp"

namespace hattr::io::detail {

static_assert(FLT_EVAL_METHOD == 0, "the predictions must round to double at every step (no x87 extended precision)");

/// A non-finite prediction (from values near the largest double) becomes 0, so that every
/// platform predicts the same bits (NaNs' bits differ between them).
inline double finiteOrZero(double value) { return std::isfinite(value) ? value : 0.0; }

/// Lossless columns: predicted in IEEE doubles, differenced as 64-bit patterns.
struct Doubles {
  using Value = double;
  static std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }
  static double fromBits(std::uint64_t b) { return std::bit_cast<double>(b); }
  static double line(double a, double b) { return finiteOrZero(2.0 * a - b); }
  static double quadratic(double a, double b, double c) { return finiteOrZero(3.0 * a - 3.0 * b + c); }
  static double cubic(double a, double b, double c, double d) { return finiteOrZero(4.0 * a - 6.0 * b + 4.0 * c - d); }
  static double plusMiss(double predicted, double earlier, double earlier_predicted) {
    return finiteOrZero(predicted + (earlier - earlier_predicted));
  }
  static double command(double guide, double user) { return finiteOrZero(guide - user); }
};

/// Columns of whole steps: predicted and differenced in wrapping 64-bit integers.
struct Steps {
  using Value = std::uint64_t;
  static std::uint64_t bits(std::uint64_t v) { return v; }
  static std::uint64_t fromBits(std::uint64_t b) { return b; }
  static std::uint64_t line(std::uint64_t a, std::uint64_t b) { return 2 * a - b; }
  static std::uint64_t quadratic(std::uint64_t a, std::uint64_t b, std::uint64_t c) { return 3 * (a - b) + c; }
  static std::uint64_t command(std::uint64_t guide, std::uint64_t user) { return guide - user; }
};

/// A position's kinematic prediction: the last position moved by the interval times
/// a·v_i + b·v_(i-1), a and b fitted to the trial by the encoder and stored in the header.
struct Kinematics {
  const double* time = nullptr;
  const double* velocity = nullptr;
  double a = 0.0;
  double b = 0.0;

  /// The prediction of position `i` (i >= 1).
  double at(const double* position, std::size_t i) const {
    return finiteOrZero(position[i - 1] + (time[i] - time[i - 1]) * (a * velocity[i] + b * velocity[i - 1]));
  }
};

/// A column's residuals under a fixed predictor: the zigzagged differences from the
/// predictions. `guide` and `user` are the axis's columns for kCommand.
template <class D>
void encodeColumn(Predictor p, const typename D::Value* column, const typename D::Value* guide,
                  const typename D::Value* user, std::uint64_t* out, std::size_t n);

/// The column back from its residuals under a fixed predictor, value by value (each
/// prediction needs the values before it).
template <class D>
void decodeColumn(Predictor p, const std::uint64_t* residuals, const typename D::Value* guide,
                  const typename D::Value* user, typename D::Value* column, std::size_t n);

// Instantiated once, in sample_codec_predictors.cpp (compiled without contraction), for the two
// kinds of column: doubles and whole steps.
extern template void encodeColumn<Doubles>(Predictor, const double*, const double*, const double*, std::uint64_t*,
                                           std::size_t);
extern template void encodeColumn<Steps>(Predictor, const std::uint64_t*, const std::uint64_t*, const std::uint64_t*,
                                         std::uint64_t*, std::size_t);
extern template void decodeColumn<Doubles>(Predictor, const std::uint64_t*, const double*, const double*, double*,
                                           std::size_t);
extern template void decodeColumn<Steps>(Predictor, const std::uint64_t*, const std::uint64_t*, const std::uint64_t*,
                                         std::uint64_t*, std::size_t);

/// A chosen channel's residuals: for each block of kBlock samples, the option (of the first
/// `options`) whose residuals take the fewest significant bits, written to `choices`.
void encodeChosenColumn(std::size_t options, const double* v, const Kinematics& k, std::uint64_t* out,
                        std::uint8_t* choices, std::size_t n);

/// A chosen channel's column back from its residuals, block by block, each with the prediction
/// its choice names.
void decodeChosenColumn(const std::uint8_t* choices, const std::uint64_t* residuals, const Kinematics& k, double* column,
                        std::size_t n);

/// a and b of a position's kinematic prediction, fitted to the trial (position [m], velocity
/// [m/s], time [s], `n` samples of each).
std::pair<double, double> fitKinematics(const double* position, const double* velocity, const double* time, std::size_t n);

}  // namespace hattr::io::detail
