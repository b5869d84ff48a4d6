#pragma once
/// Maps between the paper view's pixels and the paper plane of frame W. The view shows a
/// rectangle of the paper (x to the right, y away from the writer, which is up on the
/// screen), scaled with one scale for both axes to fit the widget and centred in it.
/// Metres inside; pixels only here. GUI thread only.

#include <Eigen/Core>
#include <QPointF>
#include <QRectF>

#include "hattr/core/types.hpp"

namespace hattr::studio {

class PaperMapping {
 public:
  /// The rectangle of the paper shown, (x_min, y_min)–(x_max, y_max) in W [m]. Throws
  /// hattr::InputError unless x_max > x_min and y_max > y_min, all finite.
  void setPaperRect(double x_min_m, double y_min_m, double x_max_m, double y_max_m);
  /// The widget's size [px] and the free margin kept around the paper [px].
  void setWidgetSize(int width_px, int height_px, int margin_px = 8);

  /// A point of the paper plane [m] → widget pixels (z is ignored).
  [[nodiscard]] QPointF toWidget(double x_m, double y_m) const noexcept;
  [[nodiscard]] QPointF toWidget(const Vec3& p_W) const noexcept { return toWidget(p_W.x(), p_W.y()); }
  /// Widget pixels → the paper plane (x, y) [m]. Points outside the paper rectangle map
  /// outside it (no clamping; see clampToPaper).
  [[nodiscard]] Eigen::Vector2d toPaper(const QPointF& px) const noexcept;
  /// The point moved into the paper rectangle [m].
  [[nodiscard]] Eigen::Vector2d clampToPaper(const Eigen::Vector2d& p_m) const noexcept;
  /// Pixels per metre of paper (the same on both axes).
  [[nodiscard]] double pixelsPerMetre() const noexcept { return scale_px_per_m_; }
  /// Where the paper rectangle lies in the widget [px].
  [[nodiscard]] QRectF paperRectPx() const noexcept;

  [[nodiscard]] double xMin() const noexcept { return x_min_m_; }
  [[nodiscard]] double yMin() const noexcept { return y_min_m_; }
  [[nodiscard]] double xMax() const noexcept { return x_max_m_; }
  [[nodiscard]] double yMax() const noexcept { return y_max_m_; }

 private:
  void update() noexcept;

  double x_min_m_ = -0.08;
  double y_min_m_ = -0.06;
  double x_max_m_ = 0.08;
  double y_max_m_ = 0.06;
  int width_px_ = 640;
  int height_px_ = 480;
  int margin_px_ = 8;
  double scale_px_per_m_ = 1.0;
  double offset_x_px_ = 0.0;  // widget x of the paper's x_min
  double offset_y_px_ = 0.0;  // widget y of the paper's y_max (top edge)
};

}  // namespace hattr::studio
