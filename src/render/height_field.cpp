#include "hattr/render/height_field.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/render/gaussian_field.hpp"

namespace hattr::render {

/// The triangle under a point: the cell's lower-left vertex, the position inside the cell
/// (u, v in [0, 1]) and which of its two triangles (split along u = v).
struct HeightField::Cell {
  int i;
  int j;
  double u;
  double v;
};

HeightField::HeightField(int nx, int ny, Vec3 origin_W, double spacing_m, std::vector<double> heights_m)
    : nx_(nx), ny_(ny), origin_W_(origin_W), spacing_m_(spacing_m), heights_(std::move(heights_m)) {
  HATTR_THROW_UNLESS(nx >= 2 && ny >= 2, "height field: expected at least 2×2 vertices, got {}×{}", nx, ny);
  HATTR_THROW_UNLESS(std::isfinite(spacing_m) && spacing_m > 0.0, "height field: spacing: expected > 0 m, got {}",
                     spacing_m);
  HATTR_THROW_UNLESS(heights_.size() == static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny),
                     "height field: expected {}×{} heights, got {}", nx, ny, heights_.size());
  for (std::size_t k = 0; k < heights_.size(); ++k) {
    HATTR_THROW_UNLESS(std::isfinite(heights_[k]), "height field: vertex {}: expected a finite height, got {}", k,
                       heights_[k]);
  }
  inv_spacing_ = 1.0 / spacing_m;

  // Vertex normals from central differences (one-sided at the border).
  normals_.resize(heights_.size());
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, nx - 1);
      const int j0 = std::max(j - 1, 0), j1 = std::min(j + 1, ny - 1);
      const double dhdx = (h(i1, j) - h(i0, j)) / ((i1 - i0) * spacing_m);
      const double dhdy = (h(i, j1) - h(i, j0)) / ((j1 - j0) * spacing_m);
      normals_[static_cast<std::size_t>(j * nx + i)] = Vec3(-dhdx, -dhdy, 1.0).normalized();
    }
  }
}

HeightField HeightField::fromFunction(int nx, int ny, Vec3 origin_W, double spacing_m,
                                      const std::function<double(double, double)>& height) {
  std::vector<double> heights(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      heights[static_cast<std::size_t>(j * nx + i)] = height(origin_W.x() + i * spacing_m, origin_W.y() + j * spacing_m);
    }
  }
  return HeightField(nx, ny, origin_W, spacing_m, std::move(heights));
}

HeightField HeightField::paperGrain(double size_m, int vertices, double amplitude_m, double correlation_length_m,
                                    std::uint64_t seed) {
  HATTR_THROW_UNLESS(vertices >= 2, "paper grain: vertices: expected >= 2, got {}", vertices);
  HATTR_THROW_UNLESS(size_m > 0.0, "paper grain: size: expected > 0 m, got {}", size_m);
  const double spacing = size_m / (vertices - 1);
  // A field fine enough for the grid: at least 4 cells per correlation length and per vertex.
  const double cells_per_length = std::clamp(correlation_length_m / spacing * 2.0, 4.0, 16.0);
  const CorrelatedGaussianField field({.correlation_length_m = correlation_length_m, .seed = seed,
                                       .tile_cells = 1024, .cells_per_length = cells_per_length});
  const Vec3 origin(-size_m / 2, -size_m / 2, 0.0);
  return fromFunction(vertices, vertices, origin, spacing,
                      [&](double x, double y) { return amplitude_m * field.at(x, y); });
}

HeightField HeightField::fromPgm(const std::filesystem::path& file, double size_m, double height_scale_m) {
  std::ifstream in(file, std::ios::binary);
  HATTR_THROW_UNLESS(in.good(), "{}: cannot open for reading", file.string());
  const auto fail = [&](const std::string& what) {
    return InputError(fmt::format("{}: not a grayscale PGM image: {}", file.string(), what));
  };
  // Header: magic, width, height, maxval, with '#' comments between tokens.
  const auto token = [&]() {
    std::string t;
    while (in >> t) {
      if (t.front() != '#') return t;
      std::string rest;
      std::getline(in, rest);
    }
    throw fail("the header ends early");
  };
  const std::string magic = token();
  if (magic != "P2" && magic != "P5") throw fail(fmt::format("expected magic P2 or P5, got \"{}\"", magic));
  const auto number = [&](const char* name, long lo, long hi) {
    const std::string t = token();
    long value = 0;
    try {
      std::size_t used = 0;
      value = std::stol(t, &used);
      if (used != t.size()) throw std::invalid_argument(t);
    } catch (const std::exception&) {
      throw fail(fmt::format("{}: expected an integer, got \"{}\"", name, t));
    }
    if (value < lo || value > hi) throw fail(fmt::format("{}: expected {} to {}, got {}", name, lo, hi, value));
    return value;
  };
  const long width = number("width", 2, 8192);
  const long height = number("height", 2, 8192);
  const long maxval = number("maxval", 1, 65535);
  HATTR_THROW_UNLESS(size_m > 0.0 && std::isfinite(height_scale_m), "{}: size and height scale must be finite, size > 0",
                     file.string());

  std::vector<double> heights(static_cast<std::size_t>(width * height));
  if (magic == "P5") {
    in.get();  // the single whitespace after maxval
    const int bytes = maxval > 255 ? 2 : 1;
    for (auto& hgt : heights) {
      unsigned value = 0;
      for (int b = 0; b < bytes; ++b) {
        const int c = in.get();
        if (c == EOF) throw fail(fmt::format("expected {} pixels, the data ends early", heights.size()));
        value = (value << 8) | static_cast<unsigned>(c);
      }
      if (value > static_cast<unsigned>(maxval)) throw fail(fmt::format("pixel value {} above maxval {}", value, maxval));
      hgt = value;
    }
  } else {
    for (auto& hgt : heights) hgt = static_cast<double>(number("pixel", 0, maxval));
  }
  // Image rows go top to bottom; the paper's y grows away from the writer (up the image).
  std::vector<double> grid(heights.size());
  for (long r = 0; r < height; ++r) {
    for (long c = 0; c < width; ++c) {
      grid[static_cast<std::size_t>((height - 1 - r) * width + c)] =
          heights[static_cast<std::size_t>(r * width + c)] / static_cast<double>(maxval) * height_scale_m;
    }
  }
  const double spacing = size_m / static_cast<double>(std::max(width, height) - 1);
  const Vec3 origin(-spacing * static_cast<double>(width - 1) / 2, -spacing * static_cast<double>(height - 1) / 2, 0.0);
  return HeightField(static_cast<int>(width), static_cast<int>(height), origin, spacing, std::move(grid));
}

HeightField::Cell HeightField::locate(double x_m, double y_m) const noexcept {
  // Clamp into the grid: outside, the border heights extend flat.
  const double gx = std::clamp((x_m - origin_W_.x()) * inv_spacing_, 0.0, static_cast<double>(nx_ - 1));
  const double gy = std::clamp((y_m - origin_W_.y()) * inv_spacing_, 0.0, static_cast<double>(ny_ - 1));
  const int i = std::min(static_cast<int>(gx), nx_ - 2);
  const int j = std::min(static_cast<int>(gy), ny_ - 2);
  return {i, j, gx - i, gy - j};
}

double HeightField::maxAbsHeight_m() const noexcept {
  double largest = 0.0;
  for (const double height : heights_) largest = std::max(largest, std::abs(height));
  return largest;
}

double HeightField::heightAt(double x_m, double y_m) const noexcept {
  if (flat()) return 0.0;
  const Cell c = locate(x_m, y_m);
  const double h00 = h(c.i, c.j), h11 = h(c.i + 1, c.j + 1);
  if (c.u >= c.v) return h00 + c.u * (h(c.i + 1, c.j) - h00) + c.v * (h11 - h(c.i + 1, c.j));
  return h00 + c.u * (h11 - h(c.i, c.j + 1)) + c.v * (h(c.i, c.j + 1) - h00);
}

SurfacePoint HeightField::surfaceAt(double x_m, double y_m) const noexcept {
  if (flat()) return {};
  const Cell c = locate(x_m, y_m);
  const auto at = [this](int i, int j) { return static_cast<std::size_t>(j * nx_ + i); };
  const std::size_t k00 = at(c.i, c.j), k11 = at(c.i + 1, c.j + 1);
  // Barycentric weights in the triangle under the point; the third vertex depends on the side
  // (below the diagonal, u >= v: 1 - u, u - v, v; above it: 1 - v, v - u, u), written without
  // a branch, which the pen crossing the diagonals would mispredict.
  const bool lower = c.u >= c.v;
  const std::size_t k3 = k00 + (lower ? std::size_t{1} : static_cast<std::size_t>(nx_));
  const double w00 = 1.0 - std::max(c.u, c.v);
  const double w3 = std::abs(c.u - c.v);
  const double w11 = std::min(c.u, c.v);
  SurfacePoint out;
  out.height_m = w00 * heights_[k00] + w3 * heights_[k3] + w11 * heights_[k11];
  out.normal_W = (w00 * normals_[k00] + w3 * normals_[k3] + w11 * normals_[k11]).normalized();
  return out;
}

TriangleMesh HeightField::mesh() const {
  TriangleMesh mesh;
  if (flat()) return mesh;
  mesh.vertices.reserve(heights_.size());
  for (int j = 0; j < ny_; ++j) {
    for (int i = 0; i < nx_; ++i) {
      mesh.vertices.emplace_back(origin_W_.x() + i * spacing_m_, origin_W_.y() + j * spacing_m_, h(i, j));
    }
  }
  mesh.triangles.reserve(static_cast<std::size_t>(2 * (nx_ - 1) * (ny_ - 1)));
  for (int j = 0; j + 1 < ny_; ++j) {
    for (int i = 0; i + 1 < nx_; ++i) {
      const auto v = [this](int a, int b) { return static_cast<std::uint32_t>(b * nx_ + a); };
      mesh.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      mesh.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  }
  return mesh;
}

}  // namespace hattr::render
