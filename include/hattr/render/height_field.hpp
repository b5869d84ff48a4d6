#pragma once
/// Macroscopic paper features: a height field on a regular grid, triangulated into a mesh
/// (two triangles per cell, split along the cell's diagonal — the regular-grid case of
/// Bourke's terrain triangulation). The contact query finds the triangle under the pen by
/// index, not by search, and interpolates heights (continuous across edges) and vertex
/// normals (force shading: the force direction is continuous across edges too). Outside
/// the grid, the edge heights extend flat. The same mesh is what the studio draws.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

#include "hattr/core/types.hpp"

namespace hattr::render {

/// The surface under a point of the paper plane.
struct SurfacePoint {
  double height_m = 0.0;           ///< surface height at (x, y)
  Vec3 normal_W = Vec3::UnitZ();   ///< force-shaded unit normal
};

/// A triangle mesh for drawing: vertices in W [m], triangles as vertex indices.
struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

class HeightField {
 public:
  /// Flat paper: z = 0 everywhere.
  HeightField() = default;
  /// A grid of nx × ny vertices starting at `origin_W` (x, y), `spacing_m` apart, heights
  /// row by row (y outer). Throws InputError for fewer than 2×2 vertices, a non-positive
  /// spacing or a non-finite height.
  HeightField(int nx, int ny, Vec3 origin_W, double spacing_m, std::vector<double> heights_m);

  /// Samples `height(x, y)` [m] on a grid (for analytic fields in tests and examples).
  static HeightField fromFunction(int nx, int ny, Vec3 origin_W, double spacing_m,
                                  const std::function<double(double, double)>& height);
  /// Procedural paper grain: a correlated Gaussian relief with standard deviation
  /// `amplitude_m`, on a square of `size_m` centred on the origin with `vertices` per side.
  static HeightField paperGrain(double size_m, int vertices, double amplitude_m, double correlation_length_m,
                                std::uint64_t seed);
  /// A grayscale PGM image (P2 or P5): black = 0, white = `height_scale_m`, pixels
  /// `size_m / (width − 1)` apart, centred on the origin. Throws InputError naming the file.
  static HeightField fromPgm(const std::filesystem::path& file, double size_m, double height_scale_m);

  /// The surface at (x, y). Servo-thread safe: O(1), no allocation.
  [[nodiscard]] SurfacePoint surfaceAt(double x_m, double y_m) const noexcept;
  /// Height only (same interpolation as surfaceAt).
  [[nodiscard]] double heightAt(double x_m, double y_m) const noexcept;
  /// The triangulated mesh (two triangles per cell).
  [[nodiscard]] TriangleMesh mesh() const;

  [[nodiscard]] bool flat() const noexcept { return nx_ == 0; }
  [[nodiscard]] int nx() const noexcept { return nx_; }
  [[nodiscard]] int ny() const noexcept { return ny_; }
  [[nodiscard]] double spacing_m() const noexcept { return spacing_m_; }
  [[nodiscard]] const Vec3& origin_W() const noexcept { return origin_W_; }
  /// The largest |height| of the grid's vertices [m] (0 when flat). O(vertices).
  [[nodiscard]] double maxAbsHeight_m() const noexcept;

 private:
  struct Cell;
  [[nodiscard]] Cell locate(double x_m, double y_m) const noexcept;
  [[nodiscard]] double h(int i, int j) const noexcept { return heights_[static_cast<std::size_t>(j * nx_ + i)]; }

  int nx_ = 0;
  int ny_ = 0;
  Vec3 origin_W_ = Vec3::Zero();
  double spacing_m_ = 1.0;
  double inv_spacing_ = 1.0;
  std::vector<double> heights_;
  std::vector<Vec3> normals_;  // per vertex, from central differences
};

}  // namespace hattr::render
