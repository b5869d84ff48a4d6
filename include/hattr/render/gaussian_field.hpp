#pragma once
/// A spatially correlated, zero-mean, unit-variance Gaussian random field n(x, y) on the
/// paper plane, the same at the same place and deterministic per seed. Its correlation is
/// ρ(r) = exp(−r²/ℓ²), ℓ the correlation length. Built once (white noise filtered by a
/// Gaussian kernel on a periodic tile); looked up in O(1) with bilinear interpolation, so the
/// servo thread can sample it. Used for the stochastic friction texture (Siira & Pai 1996)
/// and the procedural paper grain.

#include <cstdint>
#include <memory>
#include <vector>

namespace hattr::render {

struct GaussianFieldParams {
  double correlation_length_m = 5e-4;  ///< ℓ
  std::uint64_t seed = 1;
  int tile_cells = 1024;               ///< tile side in cells (a power of two)
  double cells_per_length = 4.0;       ///< grid cells per ℓ

  bool operator==(const GaussianFieldParams&) const = default;
};

class CorrelatedGaussianField {
 public:
  /// Throws InputError for a non-positive length or a tile that is not a power of two.
  explicit CorrelatedGaussianField(const GaussianFieldParams& params);
  /// n(x, y), periodic with period tile_m() in x and y. Servo-thread safe.
  [[nodiscard]] double at(double x_m, double y_m) const noexcept;
  [[nodiscard]] double spacing_m() const noexcept { return spacing_m_; }
  [[nodiscard]] double tile_m() const noexcept { return spacing_m_ * cells_; }
  [[nodiscard]] const GaussianFieldParams& params() const noexcept { return params_; }

 private:
  GaussianFieldParams params_;
  int cells_;
  double spacing_m_;
  double inv_spacing_;
  std::vector<float> values_;
};

/// The field for `params`, shared: built once while anyone holds it, and kept for the last two
/// asked for, so a process running study after study (a power analysis, the tests) builds its
/// paper's texture once. Each is a 1024² convolution (tens of ms; about 0.3 s under
/// AddressSanitizer) and 4 MB. Thread-safe; not for the servo thread (it may build, and locks).
std::shared_ptr<const CorrelatedGaussianField> sharedGaussianField(const GaussianFieldParams& params);

/// Deterministic standard normal numbers from a seed (splitmix64 + Box–Muller), the same
/// on every platform.
class PortableNormal {
 public:
  explicit PortableNormal(std::uint64_t seed) : state_(seed) {}
  double next() noexcept;

 private:
  std::uint64_t nextBits() noexcept;
  std::uint64_t state_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace hattr::render
