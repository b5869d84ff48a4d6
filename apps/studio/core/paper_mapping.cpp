#include "core/paper_mapping.hpp"

#include <algorithm>
#include <cmath>

#include "hattr/core/error.hpp"

namespace hattr::studio {

void PaperMapping::setPaperRect(double x_min_m, double y_min_m, double x_max_m, double y_max_m) {
  HATTR_THROW_UNLESS(std::isfinite(x_min_m) && std::isfinite(y_min_m) && std::isfinite(x_max_m) &&
                         std::isfinite(y_max_m) && x_max_m > x_min_m && y_max_m > y_min_m,
                     "paper view rectangle: expected finite x_min < x_max and y_min < y_max [m], got ({}, {})–({}, {})",
                     x_min_m, y_min_m, x_max_m, y_max_m);
  x_min_m_ = x_min_m;
  y_min_m_ = y_min_m;
  x_max_m_ = x_max_m;
  y_max_m_ = y_max_m;
  update();
}

void PaperMapping::setWidgetSize(int width_px, int height_px, int margin_px) {
  width_px_ = std::max(width_px, 1);
  height_px_ = std::max(height_px, 1);
  margin_px_ = std::clamp(margin_px, 0, std::min(width_px_, height_px_) / 4);
  update();
}

// One scale for both axes, the paper centred in what the margin leaves.
void PaperMapping::update() noexcept {
  const double w_m = x_max_m_ - x_min_m_;
  const double h_m = y_max_m_ - y_min_m_;
  const double usable_w = std::max(1.0, static_cast<double>(width_px_ - 2 * margin_px_));
  const double usable_h = std::max(1.0, static_cast<double>(height_px_ - 2 * margin_px_));
  scale_px_per_m_ = std::min(usable_w / w_m, usable_h / h_m);
  offset_x_px_ = 0.5 * (static_cast<double>(width_px_) - w_m * scale_px_per_m_);
  offset_y_px_ = 0.5 * (static_cast<double>(height_px_) - h_m * scale_px_per_m_);
}

QPointF PaperMapping::toWidget(double x_m, double y_m) const noexcept {
  return {offset_x_px_ + (x_m - x_min_m_) * scale_px_per_m_, offset_y_px_ + (y_max_m_ - y_m) * scale_px_per_m_};
}

Eigen::Vector2d PaperMapping::toPaper(const QPointF& px) const noexcept {
  return {x_min_m_ + (px.x() - offset_x_px_) / scale_px_per_m_, y_max_m_ - (px.y() - offset_y_px_) / scale_px_per_m_};
}

Eigen::Vector2d PaperMapping::clampToPaper(const Eigen::Vector2d& p_m) const noexcept {
  return {std::clamp(p_m.x(), x_min_m_, x_max_m_), std::clamp(p_m.y(), y_min_m_, y_max_m_)};
}

QRectF PaperMapping::paperRectPx() const noexcept {
  return {QPointF(offset_x_px_, offset_y_px_), QPointF(offset_x_px_ + (x_max_m_ - x_min_m_) * scale_px_per_m_,
                                                       offset_y_px_ + (y_max_m_ - y_min_m_) * scale_px_per_m_)};
}

}  // namespace hattr::studio
