#pragma once
/// The pen over the paper in 3-D, beside the top view (as the paper's Open Inventor scene): the
/// paper's relief as its shaded triangle mesh (raised so that its grain shows, by the factor the
/// read-out gives), the reference, a reviewed trial and the pen's trail on it, and the pen's
/// barrel at its tilt with its shadow and, when lifted, a line down to the paper. It draws
/// what the top view (PaperView) shows and repaints when that view does, so the window's frame
/// timer drives both; hidden, it costs nothing. The mesh is drawn once into a cached image
/// (again on a resize or new paper), so a frame draws only the image, the trails and the pen.

#include <QImage>
#include <QPointF>
#include <QWidget>
#include <utility>

#include "core/scene_camera.hpp"
#include "hattr/core/sample.hpp"
#include "hattr/render/height_field.hpp"

namespace hattr::studio {

class PaperView;
class Trail;

class PenSceneView final : public QWidget {
  Q_OBJECT

 public:
  /// Draws what `top` shows (watching its paint events, nothing more); `top` must outlive
  /// this view.
  explicit PenSceneView(PaperView* top, QWidget* parent = nullptr);

  /// The paper's relief and the rectangle of the paper shown [m] (the top view's).
  void setPaper(const render::HeightField& relief, double x_min_m, double y_min_m, double x_max_m, double y_max_m);

  /// Where the view draws a point of W: on the raised relief, at its own height above the
  /// real one.
  [[nodiscard]] Vec3 drawnPoint(const Vec3& p_W) const;
  /// The pixels of the pen's tip and of its barrel's far end, as drawn for `pen`.
  [[nodiscard]] std::pair<QPointF, QPointF> barrelPx(const Sample& pen) const;
  /// The factor the relief is raised by (1: flat paper).
  [[nodiscard]] double exaggeration() const noexcept { return exaggeration_; }
  [[nodiscard]] const SceneCamera& camera() const noexcept { return camera_; }

 protected:
  void paintEvent(QPaintEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;
  /// The top view painted: this one follows.
  bool eventFilter(QObject* watched, QEvent* event) override;

 private:
  void frameCamera();
  /// The pen's tip and its barrel's far end as drawn (W, on the raised relief).
  [[nodiscard]] std::pair<Vec3, Vec3> barrelW(const Sample& pen) const;
  [[nodiscard]] render::HeightField drawnRelief() const;
  void drawSurface();
  [[nodiscard]] double surfaceHeight(double x_m, double y_m) const;
  void drawTrail(QPainter& painter, const Trail& trail, const QColor& colour, double width_px) const;
  void drawPen(QPainter& painter, const Sample& pen) const;

  const PaperView* top_;
  render::HeightField relief_;
  render::HeightField drawn_relief_;  // raised and averaged per cell: what the view stands things on
  double x_min_m_ = -0.1, y_min_m_ = -0.1, x_max_m_ = 0.1, y_max_m_ = 0.1;
  double exaggeration_ = 1.0;
  SceneCamera camera_;
  QImage surface_;  // the shaded mesh at the widget's size; null: to be drawn
};

}  // namespace hattr::studio
