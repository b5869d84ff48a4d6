#include "hattr/render/gaussian_field.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

#include "hattr/core/error.hpp"

namespace hattr::render {

std::uint64_t PortableNormal::nextBits() noexcept {
  std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

double PortableNormal::next() noexcept {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  // Two uniforms in (0, 1] from the top 53 bits.
  const double u1 = (static_cast<double>(nextBits() >> 11) + 1.0) * 0x1.0p-53;
  const double u2 = static_cast<double>(nextBits() >> 11) * 0x1.0p-53;
  const double radius = std::sqrt(-2.0 * std::log(u1));
  spare_ = radius * std::sin(2.0 * std::numbers::pi * u2);
  has_spare_ = true;
  return radius * std::cos(2.0 * std::numbers::pi * u2);
}

CorrelatedGaussianField::CorrelatedGaussianField(const GaussianFieldParams& params)
    : params_(params), cells_(params.tile_cells) {
  HATTR_THROW_UNLESS(std::isfinite(params.correlation_length_m) && params.correlation_length_m > 0.0,
                     "gaussian field: correlation_length_m: expected > 0, got {}", params.correlation_length_m);
  HATTR_THROW_UNLESS(cells_ >= 16 && (cells_ & (cells_ - 1)) == 0,
                     "gaussian field: tile_cells: expected a power of two >= 16, got {}", cells_);
  HATTR_THROW_UNLESS(params.cells_per_length >= 1.0 && params.cells_per_length <= 64.0,
                     "gaussian field: cells_per_length: expected 1 to 64, got {}", params.cells_per_length);
  spacing_m_ = params.correlation_length_m / params.cells_per_length;
  inv_spacing_ = 1.0 / spacing_m_;

  // White noise on the tile.
  const std::size_t n = static_cast<std::size_t>(cells_);
  std::vector<double> noise(n * n);
  PortableNormal normal(params.seed);
  for (auto& v : noise) v = normal.next();

  // Gaussian kernel of standard deviation ℓ/2 (in cells): filtering white noise with it
  // gives the correlation exp(−r²/ℓ²). Normalized so the field has unit variance.
  const double sigma_cells = params.cells_per_length / 2.0;
  const int half = static_cast<int>(std::ceil(4.0 * sigma_cells));
  std::vector<double> kernel(static_cast<std::size_t>(2 * half + 1));
  double sum_sq = 0.0;
  for (int k = -half; k <= half; ++k) {
    const double w = std::exp(-0.5 * k * k / (sigma_cells * sigma_cells));
    kernel[static_cast<std::size_t>(k + half)] = w;
    sum_sq += w * w;
  }
  for (auto& w : kernel) w /= std::sqrt(sum_sq);  // 1-D unit gain in variance; 2-D is the product

  // Separable periodic convolution: rows, then columns.
  const auto wrap = [n](long i) { return static_cast<std::size_t>(i) & (n - 1); };
  std::vector<double> rows(n * n, 0.0);
  for (std::size_t y = 0; y < n; ++y) {
    for (std::size_t x = 0; x < n; ++x) {
      double acc = 0.0;
      for (int k = -half; k <= half; ++k) acc += kernel[static_cast<std::size_t>(k + half)] * noise[y * n + wrap(static_cast<long>(x) + k)];
      rows[y * n + x] = acc;
    }
  }
  // Bilinear interpolation between nodes lowers the variance inside a cell. Its average over
  // the cell, for the correlation ρ(d) = exp(−d²/ℓ²) between the four corners, is computed by
  // quadrature and divided out, so the field has unit variance over the plane.
  const double rho_side = std::exp(-1.0 / (params.cells_per_length * params.cells_per_length));
  const double rho_diagonal = rho_side * rho_side;
  double mean_variance = 0.0;
  constexpr int kQuadrature = 32;
  for (int a = 0; a < kQuadrature; ++a) {
    for (int b = 0; b < kQuadrature; ++b) {
      const double u = (a + 0.5) / kQuadrature, v = (b + 0.5) / kQuadrature;
      const double w[4] = {(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v};  // corners 00, 10, 01, 11
      const double side = 2 * (w[0] * w[1] + w[2] * w[3] + w[0] * w[2] + w[1] * w[3]);
      const double diagonal = 2 * (w[0] * w[3] + w[1] * w[2]);
      mean_variance += w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + w[3] * w[3] + side * rho_side + diagonal * rho_diagonal;
    }
  }
  const double gain = 1.0 / std::sqrt(mean_variance / (kQuadrature * kQuadrature));

  values_.resize(n * n);
  for (std::size_t y = 0; y < n; ++y) {
    for (std::size_t x = 0; x < n; ++x) {
      double acc = 0.0;
      for (int k = -half; k <= half; ++k) acc += kernel[static_cast<std::size_t>(k + half)] * rows[wrap(static_cast<long>(y) + k) * n + x];
      values_[y * n + x] = static_cast<float>(gain * acc);
    }
  }
}

double CorrelatedGaussianField::at(double x_m, double y_m) const noexcept {
  const double gx = x_m * inv_spacing_;
  const double gy = y_m * inv_spacing_;
  const double fx = std::floor(gx);
  const double fy = std::floor(gy);
  const double u = gx - fx;
  const double v = gy - fy;
  const auto mask = static_cast<std::int64_t>(cells_ - 1);
  const auto ix = static_cast<std::int64_t>(fx);
  const auto iy = static_cast<std::int64_t>(fy);
  const auto x0 = static_cast<std::size_t>(ix & mask);
  const auto x1 = static_cast<std::size_t>((ix + 1) & mask);
  const auto y0 = static_cast<std::size_t>(iy & mask) * static_cast<std::size_t>(cells_);
  const auto y1 = static_cast<std::size_t>((iy + 1) & mask) * static_cast<std::size_t>(cells_);
  const double a = values_[y0 + x0] + u * (values_[y0 + x1] - values_[y0 + x0]);
  const double b = values_[y1 + x0] + u * (values_[y1 + x1] - values_[y1 + x0]);
  return a + v * (b - a);
}

std::shared_ptr<const CorrelatedGaussianField> sharedGaussianField(const GaussianFieldParams& params) {
  // The fields still held anywhere (weak) and the last two asked for (kept alive), newest last;
  // never destroyed, so a thread asking while the program exits finds it whole.
  struct Cache {
    std::mutex mutex;
    std::vector<std::weak_ptr<const CorrelatedGaussianField>> known;
    std::vector<std::shared_ptr<const CorrelatedGaussianField>> recent;
  };
  static Cache& cache = *new Cache;
  auto& [mutex, known, recent] = cache;
  constexpr std::size_t kKept = 2;
  const std::lock_guard lock(mutex);
  std::erase_if(known, [](const auto& w) { return w.expired(); });
  std::shared_ptr<const CorrelatedGaussianField> field;
  for (const auto& w : known) {
    auto held = w.lock();
    if (held && held->params() == params) field = std::move(held);
  }
  if (!field) {
    field = std::make_shared<const CorrelatedGaussianField>(params);
    known.push_back(field);
  }
  std::erase(recent, field);
  recent.push_back(field);
  if (recent.size() > kKept) recent.erase(recent.begin());
  return field;
}

}  // namespace hattr::render
