#pragma once
/// Seeded random numbers for the simulation, the same on every standard library: the
/// 64-bit Mersenne Twister (its output is fixed by the C++ standard), SplitMix64 to derive
/// independent streams from one seed, and Box–Muller for normal draws (std::normal_distribution
/// is implementation-defined, so it is not used).

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace hattr::sim::detail {

/// SplitMix64 (Steele, Lea & Flood 2014): a well-mixed 64-bit value from `x`.
constexpr std::uint64_t splitMix64(std::uint64_t x) noexcept {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

/// The seed of an independent stream `stream` derived from `seed`.
constexpr std::uint64_t streamSeed(std::uint64_t seed, std::uint64_t stream) noexcept {
  return splitMix64(splitMix64(seed) ^ splitMix64(stream + 0x632BE59BD9B4E019ULL));
}

/// Standard normal draws from a seeded engine.
class NormalSource {
 public:
  explicit NormalSource(std::uint64_t seed) : engine_(seed) {}

  /// A uniform draw in (0, 1): 53 random bits, never 0.
  double uniform() noexcept {
    return (static_cast<double>(engine_() >> 11) + 0.5) * 0x1.0p-53;
  }

  /// A standard normal draw (Box–Muller; the second value of each pair is kept for the next call).
  double normal() noexcept {
    if (have_spare_) {
      have_spare_ = false;
      return spare_;
    }
    const double radius = std::sqrt(-2.0 * std::log(uniform()));
    const double angle = 2.0 * std::numbers::pi * uniform();
    spare_ = radius * std::sin(angle);
    have_spare_ = true;
    return radius * std::cos(angle);
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool have_spare_ = false;
};

}  // namespace hattr::sim::detail
