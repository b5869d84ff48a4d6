#pragma once
/// Drawing a trail's strokes, shared by the top view and the 3-D view. Qt's raster engine
/// strokes a long, wide, antialiased polyline slowly (about 3 ms for 1300 points at 2.5 px):
/// round-capped segments look the same and take a fraction of that, and points closer than a
/// pixel to the last one drawn add nothing to see, so they are skipped.

#include <QLineF>
#include <QPainter>
#include <QVector>

#include "core/series.hpp"

namespace hattr::studio {

/// Points of a stroke closer than this to the last point drawn are skipped [px].
inline constexpr double kTrailMinStep_px = 1.0;

/// Draws `trail` in `colour` at `width_px`, each point of the paper [m] placed by
/// `to_pixels(const Eigen::Vector2d&) -> QPointF`. A stroke of one point is a dot.
template <typename ToPixels>
void drawTrailStrokes(QPainter& painter, const Trail& trail, const QColor& colour, double width_px, ToPixels to_pixels) {
  painter.setPen(QPen(colour, width_px, Qt::SolidLine, Qt::RoundCap));
  QVector<QLineF> lines;
  for (const auto& stroke : trail.strokes()) {
    if (stroke.empty()) continue;
    QPointF last = to_pixels(stroke.front());
    if (stroke.size() == 1) {
      painter.drawPoint(last);
      continue;
    }
    lines.clear();
    for (std::size_t i = 1; i < stroke.size(); ++i) {
      const QPointF p = to_pixels(stroke[i]);
      if (i + 1 < stroke.size() && (p - last).manhattanLength() < kTrailMinStep_px) continue;
      lines.append(QLineF(last, p));
      last = p;
    }
    painter.drawLines(lines);
  }
}

}  // namespace hattr::studio
