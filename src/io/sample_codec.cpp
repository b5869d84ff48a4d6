// The compact sample encoding (include/hattr/io/sample_codec.hpp). Compiled with
// -ffp-contract=off (src/CMakeLists.txt): the predictions must round the same in every build.
//
// Two revisions are read: hsc1 (a fixed predictor per channel, byte planes; what schema 4
// first wrote) and hsc2 (what this build writes: a predictor chosen per block of samples, and
// the measured channels coded as bit lengths and bits). docs/study-store.md has both layouts.

#include "hattr/io/sample_codec.hpp"

#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>
#include <type_traits>

#include "hattr/core/error.hpp"

namespace hattr::io {
namespace {

static_assert(std::endian::native == std::endian::little, "the sample encoding is little-endian");
static_assert(FLT_EVAL_METHOD == 0, "the predictions must round to double at every step (no x87 extended precision)");

constexpr char kMagicV1[4] = {'H', 'S', 'C', '\x01'};  // hattr sample columns, revision 1
constexpr char kMagicV2[4] = {'H', 'S', 'C', '\x02'};  // revision 2
constexpr std::size_t kHeaderBytes = 12;              // magic, u32 count, u16 channels, u8 flags, u8 0
constexpr std::size_t kChannelBytesV1 = 10;           // u8 channel, u8 predictor, f64 step
constexpr std::size_t kChannelBytesV2 = 11;           // u8 channel, u8 predictor, u8 coding, f64 step
constexpr std::size_t kBlock = 128;                   // samples per predictor choice (hsc2)
constexpr std::uint8_t kQuantized = 1;
constexpr double kLargestSteps = 2251799813685248.0;  // 2^51: below it llround(k·step / step) is k again

/// How a channel's value is predicted from what was decoded before it.
enum class Predictor : std::uint8_t {
  kPrevious = 0,          ///< the last value (flags, raw pressure)
  kLine = 1,              ///< through the last two (time, tilt)
  kQuadratic = 2,         ///< through the last three (hsc1's continuous channels)
  kCommand = 3,           ///< the commanded force: guidance force minus the user's force, same axis
  kChosen = 4,            ///< hsc2: one of the options below, chosen per block of samples
  kChosenKinematic = 5,   ///< hsc2: the same, or from the axis's velocity (positions)
};

/// The predictions a kChosen channel's blocks choose from; kChosenKinematic adds the last two.
enum class Option : std::uint8_t {
  kPrevious = 0,            ///< the last value
  kLine = 1,                ///< through the last two
  kQuadratic = 2,           ///< through the last three
  kCubic = 3,               ///< through the last four
  kPeriodic4 = 4,           ///< the quadratic, plus what it missed 4 samples before
  kPeriodic8 = 5,           ///< the quadratic, plus what it missed 8 samples before
  kKinematic = 6,           ///< the last position moved by the interval times a·v_i + b·v_(i-1)
  kKinematicPeriodic4 = 7,  ///< that, plus what it missed 4 samples before
};
constexpr std::size_t kOptions = 6;           // kPrevious .. kPeriodic8
constexpr std::size_t kKinematicOptions = 8;  // and the two kinematic ones
static_assert(kOptions == static_cast<std::size_t>(Option::kKinematic) &&
              kKinematicOptions == static_cast<std::size_t>(Option::kKinematicPeriodic4) + 1);

/// How a channel's residuals are laid out before zstd (hsc2).
enum class Coding : std::uint8_t {
  kBytePlanes = 0,  ///< all first bytes, then all second bytes, ... (with the other such channels)
  kBitLengths = 1,  ///< each residual's bit length (as a change from the last), then its bits below the top one
};

/// The user's and the guidance force channel of a commanded-force channel's axis.
std::pair<Channel, Channel> commandParts(Channel cmd) {
  switch (cmd) {
    case Channel::kCmdFx: return {Channel::kFx, Channel::kGuideFx};
    case Channel::kCmdFy: return {Channel::kFy, Channel::kGuideFy};
    default: return {Channel::kFz, Channel::kGuideFz};
  }
}

bool isCommand(Channel c) { return c == Channel::kCmdFx || c == Channel::kCmdFy || c == Channel::kCmdFz; }
bool isPosition(Channel c) { return c == Channel::kX || c == Channel::kY || c == Channel::kZ; }
bool isVelocity(Channel c) { return c == Channel::kVx || c == Channel::kVy || c == Channel::kVz; }
bool isUserForce(Channel c) { return c == Channel::kFx || c == Channel::kFy || c == Channel::kFz; }

Channel velocityOf(Channel position) {
  return position == Channel::kX ? Channel::kVx : position == Channel::kY ? Channel::kVy : Channel::kVz;
}

bool stores(std::span<const Channel> channels, Channel c) {
  return std::find(channels.begin(), channels.end(), c) != channels.end();
}

std::size_t columnOf(std::span<const Channel> channels, Channel c) {
  return static_cast<std::size_t>(std::find(channels.begin(), channels.end(), c) - channels.begin());
}

/// The predictor of each channel: `chosen` is what a continuous channel gets (kQuadratic in
/// hsc1, kChosen in hsc2); the commanded force needs its axis's other two channels.
Predictor fixedOrChosen(Channel c, std::span<const Channel> channels, Predictor chosen) {
  if (isCommand(c)) {
    const auto [user, guide] = commandParts(c);
    return stores(channels, user) && stores(channels, guide) ? Predictor::kCommand : chosen;
  }
  switch (c) {
    case Channel::kContact:
    case Channel::kPenDown:
    case Channel::kPressure: return Predictor::kPrevious;
    case Channel::kTime:
    case Channel::kAzimuth:
    case Channel::kAltitude: return Predictor::kLine;
    default: return chosen;
  }
}

Predictor predictorV1(Channel c, std::span<const Channel> channels) {
  return fixedOrChosen(c, channels, Predictor::kQuadratic);
}

/// hsc2: lossless continuous channels choose per block, and a position whose velocity and time
/// are stored may be predicted from them. Whole steps keep hsc1's quadratic: choosing gains them
/// under 1 % (docs/study-store.md) and would cost a third more time to encode.
Predictor predictorV2(Channel c, std::span<const Channel> channels, bool quantized) {
  if (quantized) return fixedOrChosen(c, channels, Predictor::kQuadratic);
  const bool kinematic = isPosition(c) && stores(channels, velocityOf(c)) && stores(channels, Channel::kTime);
  return fixedOrChosen(c, channels, kinematic ? Predictor::kChosenKinematic : Predictor::kChosen);
}

/// hsc2: the measured channels (positions, velocities, the user's force) keep noise in their
/// last digits, and are coded as bit lengths and bits when lossless; the others as byte planes.
Coding codingV2(Channel c, bool quantized) {
  return !quantized && (isPosition(c) || isVelocity(c) || isUserForce(c)) ? Coding::kBitLengths : Coding::kBytePlanes;
}

std::size_t optionCount(Predictor p) {
  return p == Predictor::kChosenKinematic ? kKinematicOptions : p == Predictor::kChosen ? kOptions : 0;
}

// ---- Predictions: doubles (lossless) and whole steps (declared resolution) ----------------

std::uint64_t zigzag(std::uint64_t difference) { return (difference << 1) ^ (0 - (difference >> 63)); }
std::uint64_t unzigzag(std::uint64_t z) { return (z >> 1) ^ (0 - (z & 1)); }

/// A non-finite prediction (from values near the largest double) becomes 0, so that every
/// platform predicts the same bits (NaNs' bits differ between them).
double finiteOrZero(double value) { return std::isfinite(value) ? value : 0.0; }

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

/// The prediction of value `i` of a column from the values before it (fewer at its start).
template <class D>
typename D::Value predict(Predictor p, const typename D::Value* column, std::size_t i) {
  if (i == 0) return 0;
  if (p == Predictor::kPrevious || i == 1) return column[i - 1];
  if (p == Predictor::kLine || i == 2) return D::line(column[i - 1], column[i - 2]);
  return D::quadratic(column[i - 1], column[i - 2], column[i - 3]);
}

/// A position's kinematic prediction: the last position moved by the interval times
/// a·v_i + b·v_(i-1), a and b fitted to the trial by the encoder and stored in the header.
struct Kinematics {
  const double* time = nullptr;
  const double* velocity = nullptr;
  double a = 0.0;
  double b = 0.0;

  double at(const double* position, std::size_t i) const {
    return finiteOrZero(position[i - 1] + (time[i] - time[i - 1]) * (a * velocity[i] + b * velocity[i - 1]));
  }
};

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

template <class D>
std::uint64_t residualOf(typename D::Value value, typename D::Value predicted) {
  return zigzag(D::bits(value) - D::bits(predicted));
}

template <class D>
typename D::Value valueOf(std::uint64_t residual, typename D::Value predicted) {
  return D::fromBits(unzigzag(residual) + D::bits(predicted));
}

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

// ---- Layouts: byte planes, and bit lengths with bits ------------------------------------

/// Byte planes: byte b of every word, for b = 0..7 (smooth data leaves long runs in the
/// high planes).
void appendShuffled(std::string& out, const std::uint64_t* words, std::size_t n) {
  const std::size_t at = out.size();
  out.resize(at + n * 8);
  char* planes = out.data() + at;
  for (std::size_t w = 0; w < n; ++w) {
    for (std::size_t b = 0; b < 8; ++b) planes[b * n + w] = static_cast<char>(words[w] >> (8 * b));
  }
}

void unshuffle(std::string_view planes, std::uint64_t* words) {
  const std::size_t n = planes.size() / 8;
  const auto* bytes = reinterpret_cast<const unsigned char*>(planes.data());
  for (std::size_t w = 0; w < n; ++w) {
    std::uint64_t word = 0;
    for (std::size_t b = 0; b < 8; ++b) word |= static_cast<std::uint64_t>(bytes[b * n + w]) << (8 * b);
    words[w] = word;
  }
}

/// Bits appended least significant first, 64 at a time.
class BitWriter {
 public:
  explicit BitWriter(std::string& out) : out_(out) {}
  /// The low `count` bits of `bits` (count < 64).
  void put(std::uint64_t bits, int count) {
    if (count == 0) return;
    bits &= (std::uint64_t{1} << count) - 1;
    pending_ |= bits << filled_;
    if (filled_ + count < 64) {
      filled_ += count;
      return;
    }
    char word[8];
    std::memcpy(word, &pending_, 8);
    out_.append(word, 8);
    pending_ = filled_ == 0 ? 0 : bits >> (64 - filled_);
    filled_ = filled_ + count - 64;
  }
  void finish() {
    char word[8];
    std::memcpy(word, &pending_, 8);
    out_.append(word, static_cast<std::size_t>((filled_ + 7) / 8));
    pending_ = 0;
    filled_ = 0;
  }

 private:
  std::string& out_;
  std::uint64_t pending_ = 0;
  int filled_ = 0;  // always < 64
};

/// Reads what BitWriter wrote. The caller checks first that the bytes hold every bit it will
/// read.
class BitReader {
 public:
  explicit BitReader(std::string_view bytes) : bytes_(bytes) {}
  /// The next `count` bits (count < 64).
  std::uint64_t get(int count) {
    const std::size_t byte = position_ / 8;
    const auto shift = static_cast<int>(position_ % 8);
    std::uint64_t value = load(byte) >> shift;
    if (shift + count > 64) value |= load(byte + 8) << (64 - shift);
    position_ += static_cast<std::size_t>(count);
    return count == 0 ? 0 : value & ((std::uint64_t{1} << count) - 1);
  }
  /// True when every byte was read and the last one's unused bits are 0.
  bool atCleanEnd() const {
    if ((position_ + 7) / 8 != bytes_.size()) return false;
    return position_ % 8 == 0 || (static_cast<unsigned char>(bytes_.back()) >> (position_ % 8)) == 0;
  }

 private:
  /// Up to 8 bytes from `at`, those past the end read as 0.
  std::uint64_t load(std::size_t at) const {
    std::uint64_t word = 0;
    if (at < bytes_.size()) std::memcpy(&word, bytes_.data() + at, std::min<std::size_t>(8, bytes_.size() - at));
    return word;
  }

  std::string_view bytes_;
  std::size_t position_ = 0;  // in bits
};

/// Residuals as bit lengths and bits: each length as its change from the last one (a byte),
/// then, after every such channel's lengths, the bits below each residual's top bit (the top
/// bit is 1 by definition).
void appendLengthChanges(std::string& out, const std::uint64_t* words, std::size_t n) {
  const std::size_t at = out.size();
  out.resize(at + n);
  int last = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto length = static_cast<int>(std::bit_width(words[i]));
    out[at + i] = static_cast<char>(static_cast<std::uint8_t>(length - last));
    last = length;
  }
}

void appendBitsBelowTop(BitWriter& bits, const std::uint64_t* words, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const auto length = static_cast<int>(std::bit_width(words[i]));
    if (length > 1) bits.put(words[i], length - 1);
  }
}

/// The bit lengths of a column's residuals back from their changes, and how many bits follow.
std::uint64_t readBitLengths(const unsigned char* changes, std::uint8_t* lengths, std::size_t n, std::string_view name) {
  int last = 0;
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    last = static_cast<std::uint8_t>(last + changes[i]);
    HATTR_THROW_UNLESS(last <= 64, "samples: channel {}, sample {}: a residual of {} bits, expected at most 64 (damaged)",
                       name, i, last);
    lengths[i] = static_cast<std::uint8_t>(last);
    total += last > 1 ? static_cast<std::uint64_t>(last - 1) : 0;
  }
  return total;
}

void readBits(BitReader& bits, const std::uint8_t* lengths, std::uint64_t* words, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const int length = lengths[i];
    words[i] = length == 0 ? 0 : (std::uint64_t{1} << (length - 1)) | bits.get(length - 1);
  }
}

template <class T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <class T>
T get(std::string_view blob, std::size_t at) {
  T value;
  std::memcpy(&value, blob.data() + at, sizeof(T));
  return value;
}

std::string_view nameOf(Channel c) { return channelInfo(c).name; }

/// zstd's contexts, one of each per thread, kept for the thread's life.
ZSTD_CCtx* compressionContext() {
  thread_local const std::unique_ptr<ZSTD_CCtx, decltype(&ZSTD_freeCCtx)> context(ZSTD_createCCtx(), &ZSTD_freeCCtx);
  HATTR_THROW_UNLESS(context != nullptr, "sample encoding: zstd: out of memory");
  return context.get();
}

ZSTD_DCtx* decompressionContext() {
  thread_local const std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> context(ZSTD_createDCtx(), &ZSTD_freeDCtx);
  HATTR_THROW_UNLESS(context != nullptr, "samples: zstd: out of memory");
  return context.get();
}

/// `content` as one zstd frame with its checksum, each part (ending at `ends`) flushed into
/// zstd blocks of its own.
std::string compressInParts(std::string_view content, std::span<const std::size_t> ends, int level) {
  ZSTD_CCtx* context = compressionContext();
  ZSTD_CCtx_reset(context, ZSTD_reset_session_and_parameters);
  ZSTD_CCtx_setParameter(context, ZSTD_c_compressionLevel, level);
  ZSTD_CCtx_setParameter(context, ZSTD_c_checksumFlag, 1);
  const std::size_t pledged = ZSTD_CCtx_setPledgedSrcSize(context, content.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(pledged), "sample encoding: zstd: {}", ZSTD_getErrorName(pledged));
  std::string frame(ZSTD_compressBound(content.size()) + 64 * ends.size(), '\0');
  ZSTD_outBuffer out{frame.data(), frame.size(), 0};
  std::size_t from = 0;
  for (std::size_t e = 0; e < ends.size(); ++e) {
    ZSTD_inBuffer in{content.data() + from, ends[e] - from, 0};
    const ZSTD_EndDirective mode = e + 1 == ends.size() ? ZSTD_e_end : ZSTD_e_flush;
    for (;;) {
      const std::size_t left = ZSTD_compressStream2(context, &out, &in, mode);
      HATTR_THROW_UNLESS(!ZSTD_isError(left), "sample encoding: zstd: {}", ZSTD_getErrorName(left));
      HATTR_DEMAND(left == 0 || out.pos < out.size, "zstd's output buffer was sized by ZSTD_compressBound");
      if (left == 0 && in.pos == in.size) break;
    }
    from = ends[e];
  }
  frame.resize(out.pos);
  return frame;
}

/// One whole zstd frame (RFC 8878) that declares `content_size` bytes, with its content's
/// checksum, and small enough to hold them: checked before anything is allocated.
void checkFrame(std::string_view frame, std::uint64_t content_size) {
  HATTR_THROW_UNLESS(ZSTD_getFrameContentSize(frame.data(), frame.size()) == content_size,
                     "samples: the compressed residuals are not one zstd frame of {} bytes", content_size);
  const std::size_t whole = ZSTD_findFrameCompressedSize(frame.data(), frame.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(whole) && whole == frame.size(),
                     "samples: the compressed residuals are not exactly one zstd frame ({} bytes stored)", frame.size());
  // The frame header descriptor follows the 4-byte magic number; bit 2 says a checksum ends it.
  HATTR_THROW_UNLESS(frame.size() > 4 && (static_cast<unsigned char>(frame[4]) & 0x04) != 0,
                     "samples: the compressed residuals carry no checksum");
  // A zstd block of at most 128 KiB takes at least 4 bytes (an RLE block): no more content fits.
  HATTR_THROW_UNLESS(content_size <= (frame.size() / 4 + 1) * 131072,
                     "samples: {} bytes of compressed residuals cannot hold {} bytes", frame.size(), content_size);
}

/// The frame's content, decompressed and checked against the header outside it (which must be
/// its first `header_bytes` bytes).
std::unique_ptr<char[]> decompressContent(std::string_view blob, std::size_t header_bytes, std::uint64_t content_size) {
  const std::string_view frame = blob.substr(header_bytes + 8);
  checkFrame(frame, content_size);
  auto content = std::make_unique_for_overwrite<char[]>(content_size);
  const std::size_t got = ZSTD_decompressDCtx(decompressionContext(), content.get(), content_size, frame.data(), frame.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(got) && got == content_size, "samples: the compressed residuals are damaged: {}",
                     ZSTD_isError(got) ? ZSTD_getErrorName(got) : "short");
  HATTR_THROW_UNLESS(std::memcmp(content.get(), blob.data(), header_bytes) == 0,
                     "samples: the encoded block's header is damaged (it differs from its checksummed copy)");
  return content;
}

/// In whole steps the commanded force is predicted from its parts only where all three share
/// the step (else their difference is not in its steps): a quadratic otherwise.
Predictor stepPredictor(Predictor p, std::span<const Channel> channels, std::span<const double> steps, std::size_t c) {
  if (p != Predictor::kCommand) return p;
  const auto [user, guide] = commandParts(channels[c]);
  const bool same = steps[c] == steps[columnOf(channels, user)] && steps[c] == steps[columnOf(channels, guide)];
  return same ? Predictor::kCommand : Predictor::kQuadratic;
}

/// The columns in the order they can be decoded: positions predicted from their velocities
/// after those, every commanded force after its parts.
std::vector<std::size_t> decodingOrder(std::span<const Predictor> predictors) {
  const auto group = [](Predictor p) { return p == Predictor::kChosenKinematic ? 1 : p == Predictor::kCommand ? 2 : 0; };
  std::vector<std::size_t> order;
  for (int g = 0; g < 3; ++g) {
    for (std::size_t c = 0; c < predictors.size(); ++c) {
      if (group(predictors[c]) == g) order.push_back(c);
    }
  }
  return order;
}

/// The header's first 12 bytes, checked against what the store says the blob holds.
struct BlockHeader {
  std::size_t n = 0;
  std::size_t m = 0;
  bool quantized = false;
};

BlockHeader readBlockHeader(std::string_view blob, std::span<const Channel> channels, std::size_t count,
                            std::size_t channel_bytes) {
  const std::size_t n = get<std::uint32_t>(blob, 4);
  const std::size_t m = get<std::uint16_t>(blob, 8);
  const auto flags = get<std::uint8_t>(blob, 10);
  HATTR_THROW_UNLESS((flags & ~kQuantized) == 0 && get<std::uint8_t>(blob, 11) == 0,
                     "samples: the encoded block's flags are {:#04x} {:#04x}, expected 0x00 or 0x01, then 0x00", flags,
                     get<std::uint8_t>(blob, 11));
  HATTR_THROW_UNLESS(n == count, "samples: the encoded block holds {} samples, expected {}", n, count);
  HATTR_THROW_UNLESS(m == channels.size(), "samples: the encoded block holds {} channels, expected {}", m,
                     channels.size());
  HATTR_THROW_UNLESS(blob.size() >= kHeaderBytes + m * channel_bytes + 8,
                     "samples: the encoded block is cut short in its header ({} bytes)", blob.size());
  return {n, m, (flags & kQuantized) != 0};
}

/// One channel's entry of the header: its number and predictor checked, its step returned
/// (finite and > 0 in a quantized block, 0 in a lossless one).
double readChannelEntry(std::string_view blob, std::size_t at, std::size_t c, Channel channel, Predictor expected,
                        bool quantized, std::size_t step_at) {
  const auto number = get<std::uint8_t>(blob, at);
  const auto predictor = get<std::uint8_t>(blob, at + 1);
  HATTR_THROW_UNLESS(number == static_cast<std::uint8_t>(channel), "samples: encoded channel {} is number {}, expected {} ({})",
                     c, number, static_cast<int>(channel), nameOf(channel));
  HATTR_THROW_UNLESS(predictor == static_cast<std::uint8_t>(expected), "samples: channel {}: predictor {}, expected {}",
                     nameOf(channel), predictor, static_cast<int>(expected));
  const double step = get<double>(blob, at + step_at);
  HATTR_THROW_UNLESS(quantized ? std::isfinite(step) && step > 0.0 : step == 0.0, "samples: channel {}: step {} in a {} block",
                     nameOf(channel), step, quantized ? "quantized" : "lossless");
  return step;
}

/// Turns decoded whole steps into values.
void fromSteps(const std::uint64_t* k, double step, double* values, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) values[i] = static_cast<double>(static_cast<std::int64_t>(k[i])) * step;
}

/// The decoded columns as samples; every value must be finite, as a profile's are.
std::vector<Sample> toSamples(const double* values, std::span<const Channel> channels, std::size_t n) {
  std::vector<Sample> samples(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t c = 0; c < channels.size(); ++c) {
      const double v = values[c * n + i];
      HATTR_THROW_UNLESS(std::isfinite(v), "samples: channel {}, sample {}: decoded a non-finite value", nameOf(channels[c]), i);
      setChannelValue(samples[i], channels[c], v);
    }
  }
  return samples;
}

/// An hsc1 block: a fixed predictor per channel, every residual in byte planes.
std::vector<Sample> decodeRevision1(std::string_view blob, std::span<const Channel> channels, std::size_t count) {
  const BlockHeader header = readBlockHeader(blob, channels, count, kChannelBytesV1);
  const std::size_t n = header.n, m = header.m;
  std::vector<Predictor> predictors(m);
  std::vector<double> steps(m);
  for (std::size_t c = 0; c < m; ++c) {
    predictors[c] = predictorV1(channels[c], channels);
    steps[c] = readChannelEntry(blob, kHeaderBytes + c * kChannelBytesV1, c, channels[c], predictors[c], header.quantized, 2);
  }

  // The frame: the header's copy and the byte planes, under zstd's checksum.
  const std::size_t header_bytes = kHeaderBytes + m * kChannelBytesV1;
  const auto content_size = get<std::uint64_t>(blob, header_bytes);
  HATTR_THROW_UNLESS(content_size == header_bytes + n * m * 8,
                     "samples: the encoded block says {} bytes of header and residuals, expected {}", content_size,
                     header_bytes + n * m * 8);
  const auto content = decompressContent(blob, header_bytes, content_size);
  const auto words = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
  unshuffle(std::string_view(content.get() + header_bytes, n * m * 8), words.get());

  // Each column from its residuals and predictions, the commanded forces after their parts.
  const auto values = std::make_unique_for_overwrite<double[]>(n * m);
  const auto k = std::make_unique_for_overwrite<std::uint64_t[]>(header.quantized ? n * m : 0);
  for (const std::size_t c : decodingOrder(predictors)) {
    const auto [user, guide] = commandParts(channels[c]);
    if (!header.quantized) {
      const bool command = predictors[c] == Predictor::kCommand;
      decodeColumn<Doubles>(predictors[c], words.get() + c * n, command ? values.get() + columnOf(channels, guide) * n : nullptr,
                            command ? values.get() + columnOf(channels, user) * n : nullptr, values.get() + c * n, n);
      continue;
    }
    const Predictor p = stepPredictor(predictors[c], channels, steps, c);
    const bool command = p == Predictor::kCommand;
    decodeColumn<Steps>(p, words.get() + c * n, command ? k.get() + columnOf(channels, guide) * n : nullptr,
                        command ? k.get() + columnOf(channels, user) * n : nullptr, k.get() + c * n, n);
    fromSteps(k.get() + c * n, steps[c], values.get() + c * n, n);
  }
  return toSamples(values.get(), channels, n);
}

/// What an hsc2 header says about each channel, beyond the first 12 bytes.
struct LayoutV2 {
  std::vector<Predictor> predictors;  ///< as stored (kCommand even where steps make it a quadratic)
  std::vector<Predictor> effective;   ///< what predicts each column
  std::vector<Coding> codings;
  std::vector<double> steps;
  std::vector<std::pair<double, double>> kinematics;  ///< a and b, per channel (kChosenKinematic only)
  std::size_t header_bytes = 0;                        ///< up to the content size
  std::size_t chosen = 0, in_planes = 0, in_bits = 0;  ///< channels of each kind
  std::vector<std::size_t> slot;  ///< each channel's column of residuals: byte-plane channels first, in order
};

/// The parts of an hsc2 frame's content, after the header's copy, in order.
struct ContentV2 {
  std::size_t choices = 0;      ///< bytes: one per block of each chosen channel
  std::size_t planes = 0;       ///< bytes: 8 per sample of each byte-plane channel
  std::size_t lengths = 0;      ///< bytes: one per sample of each bit-length channel
  std::size_t fixed(std::size_t header_bytes) const { return header_bytes + choices + planes + lengths; }
};

/// The sizes of the content's parts before the bits, for `n` samples.
ContentV2 contentOf(const LayoutV2& layout, std::size_t n) {
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  return {blocks * layout.chosen, n * layout.in_planes * 8, n * layout.in_bits};
}

/// How many channels choose per block and how many take each layout, and each one's slot.
void countKinds(LayoutV2& layout) {
  for (std::size_t c = 0; c < layout.effective.size(); ++c) {
    if (optionCount(layout.effective[c]) > 0) ++layout.chosen;
    if (layout.codings[c] == Coding::kBitLengths) {
      ++layout.in_bits;
    } else {
      ++layout.in_planes;
    }
  }
  layout.slot.resize(layout.effective.size());
  for (std::size_t c = 0, planes = 0, bits = layout.in_planes; c < layout.slot.size(); ++c) {
    layout.slot[c] = layout.codings[c] == Coding::kBitLengths ? bits++ : planes++;
  }
}

/// The rest of an hsc2 header, each field checked against what this build writes for these
/// channels.
LayoutV2 readLayoutV2(std::string_view blob, std::span<const Channel> channels, const BlockHeader& header) {
  LayoutV2 layout;
  const std::size_t m = header.m;
  layout.predictors.resize(m);
  layout.codings.resize(m);
  layout.steps.resize(m);
  layout.kinematics.resize(m);
  std::size_t kinematic = 0;
  for (std::size_t c = 0; c < m; ++c) {
    const std::size_t at = kHeaderBytes + c * kChannelBytesV2;
    layout.predictors[c] = predictorV2(channels[c], channels, header.quantized);
    layout.steps[c] = readChannelEntry(blob, at, c, channels[c], layout.predictors[c], header.quantized, 3);
    layout.codings[c] = codingV2(channels[c], header.quantized);
    const auto coding = get<std::uint8_t>(blob, at + 2);
    HATTR_THROW_UNLESS(coding == static_cast<std::uint8_t>(layout.codings[c]), "samples: channel {}: layout {}, expected {}",
                       nameOf(channels[c]), coding, static_cast<int>(layout.codings[c]));
    if (layout.predictors[c] == Predictor::kChosenKinematic) ++kinematic;
  }
  // The kinematic predictions' a and b, after the channels.
  std::size_t at = kHeaderBytes + m * kChannelBytesV2;
  HATTR_THROW_UNLESS(blob.size() >= at + kinematic * 16 + 8, "samples: the encoded block is cut short in its header ({} bytes)",
                     blob.size());
  for (std::size_t c = 0; c < m; ++c) {
    if (layout.predictors[c] != Predictor::kChosenKinematic) continue;
    layout.kinematics[c] = {get<double>(blob, at), get<double>(blob, at + 8)};
    HATTR_THROW_UNLESS(std::isfinite(layout.kinematics[c].first) && std::isfinite(layout.kinematics[c].second),
                       "samples: channel {}: kinematic coefficients {} and {}, expected finite numbers", nameOf(channels[c]),
                       layout.kinematics[c].first, layout.kinematics[c].second);
    at += 16;
  }
  layout.header_bytes = at;
  for (std::size_t c = 0; c < m; ++c) {
    layout.effective.push_back(
        header.quantized ? stepPredictor(layout.predictors[c], channels, layout.steps, c) : layout.predictors[c]);
  }
  countKinds(layout);
  return layout;
}

/// A column's kinematic prediction reads the time and the axis's velocity, decoded before it.
Kinematics kinematicsOf(const LayoutV2& layout, std::span<const Channel> channels, std::size_t c, const double* values,
                        std::size_t n) {
  if (layout.effective[c] != Predictor::kChosenKinematic) return {};
  return {values + columnOf(channels, Channel::kTime) * n, values + columnOf(channels, velocityOf(channels[c])) * n,
          layout.kinematics[c].first, layout.kinematics[c].second};
}

/// An hsc2 block.
std::vector<Sample> decodeRevision2(std::string_view blob, std::span<const Channel> channels, std::size_t count) {
  const BlockHeader header = readBlockHeader(blob, channels, count, kChannelBytesV2);
  const std::size_t n = header.n, m = header.m;
  const LayoutV2 layout = readLayoutV2(blob, channels, header);

  // The content's size, within what its parts allow, before anything is allocated.
  const ContentV2 parts = contentOf(layout, n);
  const std::size_t fixed = parts.fixed(layout.header_bytes);
  const std::size_t most = fixed + (n * layout.in_bits * 63 + 7) / 8;
  const auto content_size = get<std::uint64_t>(blob, layout.header_bytes);
  HATTR_THROW_UNLESS(content_size >= fixed && content_size <= most,
                     "samples: the encoded block says {} bytes of header and residuals, expected {} to {}", content_size,
                     fixed, most);
  const auto content = decompressContent(blob, layout.header_bytes, content_size);
  const auto* bytes = reinterpret_cast<const unsigned char*>(content.get());

  // Each chosen channel's choices, one per block.
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<const std::uint8_t*> choices(m, nullptr);
  std::size_t at = layout.header_bytes;
  for (std::size_t c = 0; c < m; ++c) {
    const std::size_t options = optionCount(layout.effective[c]);
    if (options == 0) continue;
    choices[c] = bytes + at;
    for (std::size_t b = 0; b < blocks; ++b) {
      HATTR_THROW_UNLESS(choices[c][b] < options, "samples: channel {}, block {}: prediction {}, expected below {} (damaged)",
                         nameOf(channels[c]), b, choices[c][b], options);
    }
    at += blocks;
  }

  // The residuals: byte planes, then bit lengths and bits, each channel's in its slot.
  const auto words = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
  unshuffle(std::string_view(content.get() + at, parts.planes), words.get());
  at += parts.planes;
  std::vector<std::uint8_t> lengths(n * layout.in_bits);
  std::uint64_t total_bits = 0;
  for (std::size_t c = 0; c < m; ++c) {
    if (layout.codings[c] != Coding::kBitLengths) continue;
    const std::size_t q = layout.slot[c] - layout.in_planes;
    total_bits += readBitLengths(bytes + at + q * n, lengths.data() + q * n, n, nameOf(channels[c]));
  }
  at += parts.lengths;
  HATTR_THROW_UNLESS(content_size - at == (total_bits + 7) / 8,
                     "samples: the compressed residuals are damaged: {} bytes of bits, expected {}", content_size - at,
                     (total_bits + 7) / 8);
  BitReader bits(std::string_view(content.get() + at, content_size - at));
  for (std::size_t q = 0; q < layout.in_bits; ++q) {
    readBits(bits, lengths.data() + q * n, words.get() + (layout.in_planes + q) * n, n);
  }
  HATTR_THROW_UNLESS(bits.atCleanEnd(), "samples: the compressed residuals are damaged: their last byte has stray bits");

  // Each column from its residuals and predictions: positions after their velocities, the
  // commanded forces after their parts.
  const auto values = std::make_unique_for_overwrite<double[]>(n * m);
  const auto k = std::make_unique_for_overwrite<std::uint64_t[]>(header.quantized ? n * m : 0);
  for (const std::size_t c : decodingOrder(layout.effective)) {
    const Predictor p = layout.effective[c];
    const auto [user, guide] = commandParts(channels[c]);
    const bool command = p == Predictor::kCommand;
    if (!header.quantized) {
      double* column = values.get() + c * n;
      if (choices[c] != nullptr) {
        decodeChosenColumn(choices[c], words.get() + layout.slot[c] * n, kinematicsOf(layout, channels, c, values.get(), n), column, n);
      } else {
        decodeColumn<Doubles>(p, words.get() + layout.slot[c] * n, command ? values.get() + columnOf(channels, guide) * n : nullptr,
                              command ? values.get() + columnOf(channels, user) * n : nullptr, column, n);
      }
      continue;
    }
    decodeColumn<Steps>(p, words.get() + layout.slot[c] * n, command ? k.get() + columnOf(channels, guide) * n : nullptr,
                        command ? k.get() + columnOf(channels, user) * n : nullptr, k.get() + c * n, n);
    fromSteps(k.get() + c * n, layout.steps[c], values.get() + c * n, n);
  }
  return toSamples(values.get(), channels, n);
}

}  // namespace

const ChannelResolution& defaultResolution() {
  static const ChannelResolution resolution = [] {
    ChannelResolution r;
    r[Channel::kTime] = 1e-6;
    for (Channel c : {Channel::kX, Channel::kY, Channel::kZ}) r[c] = 1e-6;
    for (Channel c : {Channel::kVx, Channel::kVy, Channel::kVz}) r[c] = 1e-5;
    for (Channel c : {Channel::kFx, Channel::kFy, Channel::kFz, Channel::kCmdFx, Channel::kCmdFy, Channel::kCmdFz,
                      Channel::kGuideFx, Channel::kGuideFy, Channel::kGuideFz}) {
      r[c] = 1e-3;
    }
    for (Channel c : {Channel::kContact, Channel::kPenDown, Channel::kPressure}) r[c] = 1.0;
    for (Channel c : {Channel::kAzimuth, Channel::kAltitude}) r[c] = 1e-4;
    return r;
  }();
  return resolution;
}

ChannelResolution parseResolution(std::string_view json_text, std::string_view where) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: expected \"lossless\", \"default\" or an object of channel steps, got {} ({})",
                                 where, json_text, e.what()));
  }
  if (json.is_string() && json.get<std::string>() == "lossless") return {};
  if (json.is_string() && json.get<std::string>() == "default") return defaultResolution();
  HATTR_THROW_UNLESS(json.is_object(), "{}: expected \"lossless\", \"default\" or an object of channel steps, got {}",
                     where, json.dump());
  // Named channels take their step; the others keep the default's.
  ChannelResolution resolution = defaultResolution();
  for (const auto& [name, step] : json.items()) {
    const auto channel = channelFromName(name);
    HATTR_THROW_UNLESS(channel && !channelInfo(*channel).derived,
                       "{}: \"{}\": expected a stored channel (t, x, y, z, vx, vy, vz, fx, fy, fz, cmd_fx, cmd_fy, "
                       "cmd_fz, guide_fx, guide_fy, guide_fz, contact, pen_down, pressure, azimuth, altitude)",
                       where, name);
    HATTR_THROW_UNLESS(step.is_number() && std::isfinite(step.get<double>()) && step.get<double>() > 0.0,
                       "{}: \"{}\": expected a step > 0 in {}, got {}", where, name, channelInfo(*channel).unit,
                       step.dump());
    resolution[*channel] = step.get<double>();
  }
  return resolution;
}

std::string resolutionJson(const ChannelResolution& resolution) {
  if (resolution.empty()) return "\"lossless\"";
  nlohmann::json json = nlohmann::json::object();
  for (const auto& [channel, step] : resolution) json[std::string(nameOf(channel))] = step;
  return json.dump();
}

bool isEncodedSamples(std::string_view blob) noexcept { return !sampleEncodingOf(blob).empty(); }

std::string_view sampleEncodingOf(std::string_view blob) noexcept {
  if (blob.size() < sizeof kMagicV1) return {};
  if (std::memcmp(blob.data(), kMagicV1, sizeof kMagicV1) == 0) return kSampleEncodingV1;
  if (std::memcmp(blob.data(), kMagicV2, sizeof kMagicV2) == 0) return kSampleEncoding;
  return {};
}

std::string encodeSamples(std::span<const Sample> samples, std::span<const Channel> channels,
                          const ChannelResolution& resolution, int level) {
  const std::size_t n = samples.size();
  const std::size_t m = channels.size();
  HATTR_THROW_UNLESS(n <= 0xFFFFFFFFu && m >= 1 && m <= 0xFFFF, "sample encoding: {} samples on {} channels", n, m);
  HATTR_THROW_UNLESS(level >= 1 && level <= 19, "sample encoding: zstd level: expected 1 to 19, got {}", level);
  const bool quantized = !resolution.empty();

  // The header: what the blob holds, and how each channel is predicted and laid out.
  LayoutV2 layout;
  std::string blob(kMagicV2, sizeof kMagicV2);
  put<std::uint32_t>(blob, static_cast<std::uint32_t>(n));
  put<std::uint16_t>(blob, static_cast<std::uint16_t>(m));
  put<std::uint8_t>(blob, quantized ? kQuantized : 0);
  put<std::uint8_t>(blob, 0);
  for (const Channel c : channels) {
    layout.predictors.push_back(predictorV2(c, channels, quantized));
    layout.codings.push_back(codingV2(c, quantized));
    double step = 0.0;
    if (quantized) {
      const auto it = resolution.find(c);
      HATTR_THROW_UNLESS(it != resolution.end() && std::isfinite(it->second) && it->second > 0.0,
                         "sample encoding: the declared resolution has no step > 0 for channel {}", nameOf(c));
      step = it->second;
    }
    layout.steps.push_back(step);
    put<std::uint8_t>(blob, static_cast<std::uint8_t>(c));
    put<std::uint8_t>(blob, static_cast<std::uint8_t>(layout.predictors.back()));
    put<std::uint8_t>(blob, static_cast<std::uint8_t>(layout.codings.back()));
    put<double>(blob, step);
  }
  for (std::size_t c = 0; c < m; ++c) {
    layout.effective.push_back(quantized ? stepPredictor(layout.predictors[c], channels, layout.steps, c)
                                         : layout.predictors[c]);
  }
  countKinds(layout);

  // Each column as doubles (lossless) or whole steps; each sample read once.
  const auto values = std::make_unique_for_overwrite<double[]>(n * m);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t c = 0; c < m; ++c) values[c * n + i] = channelValue(samples[i], channels[c]);
  }
  const auto k = std::make_unique_for_overwrite<std::uint64_t[]>(quantized ? n * m : 0);
  for (std::size_t c = 0; quantized && c < m; ++c) {
    for (std::size_t i = 0; i < n; ++i) {
      const double v = values[c * n + i] / layout.steps[c];
      HATTR_THROW_UNLESS(std::isfinite(values[c * n + i]), "sample encoding: channel {}, sample {}: not a number: {}",
                         nameOf(channels[c]), i, values[c * n + i]);
      HATTR_THROW_UNLESS(std::abs(v) <= kLargestSteps, "sample encoding: channel {}, sample {}: {} {} is beyond 2^51 steps of {} {}",
                         nameOf(channels[c]), i, values[c * n + i], channelInfo(channels[c]).unit, layout.steps[c],
                         channelInfo(channels[c]).unit);
      k[c * n + i] = static_cast<std::uint64_t>(std::llround(v));
    }
  }

  // The kinematic predictions' a and b, fitted to this trial, after the channels.
  layout.kinematics.resize(m);
  for (std::size_t c = 0; c < m; ++c) {
    if (layout.predictors[c] != Predictor::kChosenKinematic) continue;
    layout.kinematics[c] = fitKinematics(values.get() + c * n, values.get() + columnOf(channels, velocityOf(channels[c])) * n,
                                         values.get() + columnOf(channels, Channel::kTime) * n, n);
    put<double>(blob, layout.kinematics[c].first);
    put<double>(blob, layout.kinematics[c].second);
  }
  layout.header_bytes = blob.size();

  // Each column's residuals against its predictions, zigzagged; the chosen columns' choices.
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  const auto words = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
  std::string content = blob;  // the header again, under zstd's checksum
  for (std::size_t c = 0; c < m; ++c) {
    const Predictor p = layout.effective[c];
    const auto [user, guide] = commandParts(channels[c]);
    const bool command = p == Predictor::kCommand;
    std::uint8_t* choices = nullptr;
    if (optionCount(p) > 0) {
      content.resize(content.size() + blocks);
      choices = reinterpret_cast<std::uint8_t*>(content.data() + content.size() - blocks);
    }
    if (!quantized) {
      const double* column = values.get() + c * n;
      if (choices != nullptr) {
        encodeChosenColumn(optionCount(p), column, kinematicsOf(layout, channels, c, values.get(), n),
                           words.get() + layout.slot[c] * n, choices, n);
      } else {
        encodeColumn<Doubles>(p, column, command ? values.get() + columnOf(channels, guide) * n : nullptr,
                              command ? values.get() + columnOf(channels, user) * n : nullptr, words.get() + layout.slot[c] * n, n);
      }
    } else {
      encodeColumn<Steps>(p, k.get() + c * n, command ? k.get() + columnOf(channels, guide) * n : nullptr,
                          command ? k.get() + columnOf(channels, user) * n : nullptr, words.get() + layout.slot[c] * n, n);
    }
  }

  // Then the byte-plane channels' planes, the bit-length channels' lengths, and their bits.
  const std::size_t planes_at = content.size();
  appendShuffled(content, words.get(), n * layout.in_planes);
  const std::size_t lengths_at = content.size();
  for (std::size_t q = 0; q < layout.in_bits; ++q) appendLengthChanges(content, words.get() + (layout.in_planes + q) * n, n);
  const std::size_t bits_at = content.size();
  content.reserve(bits_at + n * layout.in_bits * 8 + 8);
  BitWriter writer(content);
  for (std::size_t q = 0; q < layout.in_bits; ++q) appendBitsBelowTop(writer, words.get() + (layout.in_planes + q) * n, n);
  writer.finish();

  // Compressed, with zstd's checksum of the content: a damaged block is refused, never read as
  // samples. Each part starts a zstd block of its own (the bits are incompressible and
  // are kept raw, the others get tables of their own). The thread keeps its context (and its
  // tables) from one trial to the next.
  const std::size_t part_ends[] = {planes_at, lengths_at, bits_at, content.size()};
  put<std::uint64_t>(blob, content.size());
  blob += compressInParts(content, part_ends, level);
  return blob;
}

std::vector<Sample> decodeSamples(std::string_view blob, std::span<const Channel> channels, std::size_t count) {
  const std::string_view revision = sampleEncodingOf(blob);
  HATTR_THROW_UNLESS(!revision.empty() && blob.size() >= kHeaderBytes,
                     "samples: expected an encoded block (starting \"HSC\\x01\" or \"HSC\\x02\", at least {} bytes), got {} bytes",
                     kHeaderBytes, blob.size());
  return revision == kSampleEncoding ? decodeRevision2(blob, channels, count) : decodeRevision1(blob, channels, count);
}

}  // namespace hattr::io
