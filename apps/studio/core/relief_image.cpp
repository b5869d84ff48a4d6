#include "core/relief_image.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace hattr::studio {
namespace {

constexpr int kPaperRed = 250, kPaperGreen = 248, kPaperBlue = 240;  // warm white
constexpr double kDarkest = 45.0;                                    // gray levels below the paper colour

}  // namespace

QColor paperColour() { return {kPaperRed, kPaperGreen, kPaperBlue}; }

QImage reliefImage(const render::HeightField& relief, double x_min_m, double y_min_m, double x_max_m, double y_max_m,
                   int width_px, int height_px) {
  width_px = std::max(width_px, 1);
  height_px = std::max(height_px, 1);
  QImage image(width_px, height_px, QImage::Format_RGB32);
  if (relief.flat()) {
    image.fill(paperColour());
    return image;
  }

  // Sample the heights at pixel centres.
  std::vector<double> heights(static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px));
  const double dx = (x_max_m - x_min_m) / width_px;
  const double dy = (y_max_m - y_min_m) / height_px;
  double sum = 0.0, sum_sq = 0.0;
  for (int row = 0; row < height_px; ++row) {
    const double y = y_max_m - (row + 0.5) * dy;
    for (int col = 0; col < width_px; ++col) {
      const double h = relief.heightAt(x_min_m + (col + 0.5) * dx, y);
      heights[static_cast<std::size_t>(row) * static_cast<std::size_t>(width_px) + static_cast<std::size_t>(col)] = h;
      sum += h;
      sum_sq += h * h;
    }
  }

  // Gray levels between mean ± 2.5 sd.
  const double n = static_cast<double>(heights.size());
  const double mean = sum / n;
  const double sd = std::sqrt(std::max(0.0, sum_sq / n - mean * mean));
  const double lo = mean - 2.5 * sd;
  const double span = sd > 0.0 ? 5.0 * sd : 1.0;
  for (int row = 0; row < height_px; ++row) {
    auto* line = reinterpret_cast<QRgb*>(image.scanLine(row));
    for (int col = 0; col < width_px; ++col) {
      const double h =
          heights[static_cast<std::size_t>(row) * static_cast<std::size_t>(width_px) + static_cast<std::size_t>(col)];
      const double level = sd > 0.0 ? std::clamp((h - lo) / span, 0.0, 1.0) : 1.0;
      const int shade = static_cast<int>(std::lround((1.0 - level) * kDarkest));
      line[col] = qRgb(kPaperRed - shade, kPaperGreen - shade, kPaperBlue - shade);
    }
  }
  return image;
}

}  // namespace hattr::studio
