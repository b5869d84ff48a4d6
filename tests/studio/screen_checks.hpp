#pragma once
// What the studio tests look for in a screenshot of the main window (a widget grab offscreen,
// the X server's pixels under Xvfb), and a mouse event sent to a widget.

#include <QCoreApplication>
#include <QImage>
#include <QMouseEvent>
#include <cstdlib>

#include "hattr/core/haptic_profile.hpp"
#include "ui/main_window.hpp"
#include "ui/paper_view.hpp"

namespace hattr::studio::test {

/// True if a pixel within `radius` of p has a colour within `tolerance` (sum over R, G, B) of `colour`.
inline bool colourNear(const QImage& image, QPoint p, const QColor& colour, int radius = 1, int tolerance = 60) {
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      const QPoint q = p + QPoint(dx, dy);
      if (!image.rect().contains(q)) continue;
      const QColor c = image.pixelColor(q);
      const int d =
          std::abs(c.red() - colour.red()) + std::abs(c.green() - colour.green()) + std::abs(c.blue() - colour.blue());
      if (d <= tolerance) return true;
    }
  }
  return false;
}

/// The share of a profile's pen-down points (every `step`-th) drawn in `colour` in a shot of
/// the whole window (its paper view's pixels where the window has them).
inline double shareDrawn(const QImage& shot, const MainWindow& window, const HapticProfile& profile,
                         const QColor& colour, std::size_t step = 20) {
  const PaperView* view = window.paperView();
  const QPoint origin = view->mapTo(&window, QPoint(0, 0));
  int found = 0, total = 0;
  for (std::size_t i = 0; i < profile.size(); i += step) {
    if (!profile[i].pen_down) continue;
    const QPointF px = view->mapping().toWidget(profile[i].p_WT) + QPointF(origin);
    ++total;
    found += colourNear(shot, px.toPoint(), colour) ? 1 : 0;
  }
  return total == 0 ? 0.0 : static_cast<double>(found) / total;
}

/// A mouse event at `at` (the widget's coordinates), delivered at once.
inline void sendMouse(QWidget* widget, QEvent::Type type, QPointF at, Qt::MouseButton button, Qt::MouseButtons buttons) {
  QMouseEvent event(type, at, widget->mapToGlobal(at), button, buttons, Qt::NoModifier);
  QCoreApplication::sendEvent(widget, &event);
}

}  // namespace hattr::studio::test
