#include <cmath>
#include <memory>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "hattr/render/gaussian_field.hpp"
#include "hattr/render/height_field.hpp"
#include "hattr/render/paper_renderer.hpp"
#include "support/test_support.hpp"

namespace hattr::render {
namespace {

// ---- Texture field statistics --------------------------------------------------------------

TEST(GaussianField, HasZeroMeanUnitVarianceAndTheConfiguredCorrelationLength) {
  const std::uint64_t seed = test::testSeed(11);
  const double ell = 5e-4;
  const CorrelatedGaussianField field({.correlation_length_m = ell, .seed = seed});
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> place(0.0, field.tile_m());
  std::uniform_real_distribution<double> angle(0.0, 2 * std::numbers::pi);
  constexpr int kPlaces = 100'000;
  double sum = 0, sum_sq = 0, cross = 0;
  for (int i = 0; i < kPlaces; ++i) {
    const double x = place(rng), y = place(rng), a = angle(rng);
    const double v = field.at(x, y);
    sum += v;
    sum_sq += v * v;
    cross += v * field.at(x + ell * std::cos(a), y + ell * std::sin(a));  // a partner at distance ℓ
  }
  const double mean = sum / kPlaces;
  const double variance = sum_sq / kPlaces - mean * mean;
  const double correlation_at_ell = (cross / kPlaces - mean * mean) / variance;
  std::cout << "[ info ] mean " << mean << ", std " << std::sqrt(variance) << ", ρ(ℓ) " << correlation_at_ell
            << " (expected 0, 1, e^-1 = 0.368)\n";
  EXPECT_NEAR(mean, 0.0, 0.03) << "seed " << seed;
  EXPECT_NEAR(std::sqrt(variance), 1.0, 0.05) << "seed " << seed;
  EXPECT_NEAR(correlation_at_ell, std::exp(-1.0), 0.04) << "seed " << seed;
}

TEST(GaussianField, SameSeedSameFieldOtherSeedOtherField) {
  const CorrelatedGaussianField a({.seed = 5}), b({.seed = 5}), c({.seed = 6});
  double differences = 0;
  for (int i = 0; i < 1000; ++i) {
    const double x = i * 1.3e-4, y = i * 0.7e-4;
    EXPECT_EQ(a.at(x, y), b.at(x, y));
    differences += std::abs(a.at(x, y) - c.at(x, y));
  }
  EXPECT_GT(differences / 1000, 0.5);
}

// A paper's texture is built once and shared: the same parameters give the same field (the
// values of one built on its own), other parameters another; the last two asked for are kept.
TEST(GaussianField, SharedFieldsAreBuiltOnceForTheSameParametersAndEqualAFreshBuild) {
  const GaussianFieldParams five{.seed = 5, .tile_cells = 64};
  const auto a = sharedGaussianField(five);
  const auto b = sharedGaussianField(five);
  EXPECT_EQ(a.get(), b.get());
  auto other = sharedGaussianField({.seed = 6, .tile_cells = 64});
  EXPECT_NE(other.get(), a.get());
  const CorrelatedGaussianField fresh(five);
  for (int i = 0; i < 200; ++i) EXPECT_EQ(a->at(i * 1.3e-4, i * 0.7e-4), fresh.at(i * 1.3e-4, i * 0.7e-4));
  // Released by everyone here, a field is still kept while it is among the last two asked for.
  const std::weak_ptr<const CorrelatedGaussianField> watch = other;
  other.reset();
  ASSERT_FALSE(watch.expired());
  EXPECT_EQ(sharedGaussianField({.seed = 6, .tile_cells = 64}).get(), watch.lock().get());
  // A third field pushes the oldest released one out.
  const std::weak_ptr<const CorrelatedGaussianField> oldest = sharedGaussianField({.seed = 7, .tile_cells = 64});
  (void)sharedGaussianField({.seed = 8, .tile_cells = 64});
  (void)sharedGaussianField({.seed = 9, .tile_cells = 64});
  EXPECT_TRUE(oldest.expired());
}

TEST(GaussianField, TextureMakesFrictionVaryAroundItsMean) {
  PaperParams params;
  params.texture.sigma = 0.05;
  const PaperRenderer paper(params);
  double sum = 0, sum_sq = 0;
  constexpr int kPlaces = 20'000;
  for (int i = 0; i < kPlaces; ++i) {
    const double mu = paper.frictionAt(i * 3.1e-4, i * 1.7e-4).second;
    sum += mu;
    sum_sq += mu * mu;
  }
  const double mean = sum / kPlaces;
  EXPECT_NEAR(mean, params.friction.dynamic_coefficient, 0.005);
  EXPECT_NEAR(std::sqrt(sum_sq / kPlaces - mean * mean), params.texture.sigma, 0.005);
}

// ---- Height-field mesh --------------------------------------------------------------------------

double wave(double x, double y) { return 2e-4 * std::sin(300.0 * x) * std::cos(200.0 * y); }

/// Largest |mesh − analytic| over a fine sampling of the square [-0.01, 0.01]².
double maxMeshError(double spacing) {
  const int n = static_cast<int>(std::round(0.02 / spacing)) + 1;
  const HeightField field = HeightField::fromFunction(n, n, Vec3(-0.01, -0.01, 0), spacing, wave);
  double worst = 0.0;
  for (int j = 0; j <= 400; ++j) {
    for (int i = 0; i <= 400; ++i) {
      const double x = -0.01 + i * 5e-5, y = -0.01 + j * 5e-5;
      worst = std::max(worst, std::abs(field.heightAt(x, y) - wave(x, y)));
    }
  }
  return worst;
}

TEST(HeightField, MeshMatchesAnAnalyticFieldWithinTheTriangulationError) {
  // Linear interpolation on a triangle errs by at most h²·(|f_xx| + 2|f_xy| + |f_yy|)/2.
  const double amplitude = 2e-4, kx = 300.0, ky = 200.0;
  const double second = amplitude * (kx * kx + 2 * kx * ky + ky * ky);
  for (const double spacing : {5e-4, 2.5e-4}) {
    const double error = maxMeshError(spacing);
    EXPECT_LE(error, spacing * spacing * second / 2) << "spacing " << spacing;
  }
  // Second order: halving the spacing divides the error by about four.
  const double ratio = maxMeshError(5e-4) / maxMeshError(2.5e-4);
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.0);
}

TEST(HeightField, MeshHasTwoTrianglesPerCellOverTheSameVertices) {
  const HeightField field = HeightField::fromFunction(4, 3, Vec3(0, 0, 0), 1e-3, wave);
  const TriangleMesh mesh = field.mesh();
  EXPECT_EQ(mesh.vertices.size(), 12u);
  EXPECT_EQ(mesh.triangles.size(), 2u * 3u * 2u);
  for (const auto& v : mesh.vertices) EXPECT_NEAR(v.z(), wave(v.x(), v.y()), 1e-15);
}

// surfaceAt blends the three vertices of the triangle under the point: below a cell's diagonal
// (u > v) the corner (i+1, j), above it (i, j+1), with barycentric weights; on the diagonal the
// third vertex's weight is zero. Heights here are distinct, so a swapped vertex or weight shows.
TEST(HeightField, SurfaceAtBlendsTheTriangleUnderThePointOnEitherSideOfTheDiagonal) {
  const double spacing = 1e-3;
  const auto heights = [](double x, double y) { return 1e-4 * (1.0 + 3.0 * x / 1e-3 + 7.0 * y / 1e-3 + 11.0 * x * y / 1e-6); };
  const HeightField field = HeightField::fromFunction(3, 3, Vec3(0, 0, 0), spacing, heights);
  const double h00 = heights(0, 0), h10 = heights(spacing, 0), h01 = heights(0, spacing);
  const double h11 = heights(spacing, spacing);
  struct Place {
    double u, v;
  };
  for (const Place p : {Place{0.7, 0.2}, Place{0.2, 0.7}, Place{0.4, 0.4}, Place{0.9, 0.0}, Place{0.0, 0.9}}) {
    const bool lower = p.u >= p.v;
    const double w00 = lower ? 1.0 - p.u : 1.0 - p.v;
    const double w3 = lower ? p.u - p.v : p.v - p.u;
    const double w11 = lower ? p.v : p.u;
    const double expected = w00 * h00 + w3 * (lower ? h10 : h01) + w11 * h11;
    const SurfacePoint s = field.surfaceAt(p.u * spacing, p.v * spacing);
    EXPECT_NEAR(s.height_m, expected, 1e-15) << "u " << p.u << " v " << p.v;
    EXPECT_NEAR(s.height_m, field.heightAt(p.u * spacing, p.v * spacing), 1e-15) << "u " << p.u << " v " << p.v;
    EXPECT_NEAR(s.normal_W.norm(), 1.0, 1e-12);
  }
}

TEST(HeightField, ForceDraggedAcrossTheMeshHasNoJumpsAndTheProxyStaysOnTheSurface) {
  // Frictionless, so the only thing that could jump is the contact normal at facet edges
  // (stick–slip drops the force from μs·Fn to μd·Fn on purpose; tested above).
  PaperParams params;
  params.texture.sigma = 0.0;
  params.friction = {.static_coefficient = 0.0, .dynamic_coefficient = 0.0};
  PaperRenderer paper(params, HeightField::fromFunction(81, 81, Vec3(-0.01, -0.01, 0), 2.5e-4, wave));
  ContactForces out;
  Vec3 last = Vec3::Zero();
  double worst_jump = 0.0;
  constexpr double kStep = 2e-6;  // 125 samples per cell: edges are crossed many times
  for (int i = 0; i < 8000; ++i) {
    const double x = -0.008 + i * kStep, y = -0.006 + 0.37 * i * kStep;
    PenState pen;
    pen.p_WT = Vec3(x, y, paper.relief().heightAt(x, y) - 1e-3);
    paper.render(pen, 1e-3, out);
    ASSERT_TRUE(out.in_contact);
    const Vec3& proxy = paper.detail().proxy_W;
    ASSERT_NEAR(proxy.z(), paper.relief().heightAt(proxy.x(), proxy.y()), 1e-15) << "proxy left the surface";
    if (i > 0) worst_jump = std::max(worst_jump, (out.f_on_pen_W - last).norm());
    last = out.f_on_pen_W;
  }
  // The force is about 0.6 N; between two samples 2 µm apart it changes by far less than a
  // jump at a facet edge would make (normals of neighbouring facets differ by up to ~6°).
  std::cout << "[ info ] largest force change between samples: " << worst_jump << " N\n";
  EXPECT_LT(worst_jump, 0.01);
}

}  // namespace
}  // namespace hattr::render
