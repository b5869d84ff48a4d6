#pragma once
// What the studio tests look for in a screenshot of the main window (a widget grab offscreen,
// the X server's pixels under Xvfb), a mouse event sent to a widget, a tab clicked, the screen
// read back, and a scripted hand.

#include <QCoreApplication>
#include <QElapsedTimer>
#include <QImage>
#include <QMouseEvent>
#include <QScreen>
#include <QTabBar>
#include <QTabWidget>
#include <QtTest>
#include <algorithm>
#include <cstdlib>

#include "core/series.hpp"
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

/// Clicks the tab bar's tab `index` as a person does, and waits until it is the current one.
inline void clickTab(MainWindow& w, int index) {
  QTabBar* bar = w.tabs()->tabBar();
  QTest::mouseClick(bar, Qt::LeftButton, Qt::NoModifier, bar->tabRect(index).center());
  QTRY_COMPARE(w.tabs()->currentIndex(), index);
}

/// The window as the screen shows it (the X server's pixels under Xvfb), after it repainted;
/// saved as `file` in the working folder (the test's build folder).
inline QImage screenShot(MainWindow& w, const QString& file) {
  w.update();
  QTest::qWait(200);
  const QImage shot = w.screen()->grabWindow(w.winId()).toImage();
  shot.save(file);
  return shot;
}

/// A scripted hand: holds the left button and moves the mouse along `path` (an expert's
/// profile, shifted by `offset`) on the trial's clock while the window's activity is `during`,
/// lifting the pen when the path ends. With `mid_shot`, the window is saved there 0.6 s into
/// the trial. `ran_s`: the last trial time [s] seen while the activity ran.
inline void writeAlong(MainWindow& w, const HapticProfile& path, const Vec3& offset, MainWindow::Activity during,
                       const char* mid_shot = nullptr, double* ran_s = nullptr) {
  PaperView* view = w.paperView();
  const auto at = [&](double t_trial) {
    Playback where;
    where.load(&path);
    const Vec3 p = path[where.indexAt(std::max(0.0, t_trial))].p_WT + offset;
    return view->mapping().toWidget(p);
  };
  sendMouse(view, QEvent::MouseMove, at(0.0), Qt::NoButton, Qt::NoButton);
  sendMouse(view, QEvent::MouseButtonPress, at(0.0), Qt::LeftButton, Qt::LeftButton);
  const double lift_at_s = path.samples().back().t_s - path.samples().front().t_s;
  bool down = true;
  QElapsedTimer timer;
  timer.start();
  while (w.activity() == during && timer.elapsed() < 15000) {
    const double t_trial = w.rig().status().loop_time_s - w.rig().spec().settle_s;
    if (ran_s != nullptr) *ran_s = t_trial;
    if (down && t_trial > lift_at_s) {
      sendMouse(view, QEvent::MouseButtonRelease, at(t_trial), Qt::LeftButton, Qt::NoButton);
      down = false;
    }
    sendMouse(view, QEvent::MouseMove, at(t_trial), Qt::NoButton, down ? Qt::LeftButton : Qt::NoButton);
    if (mid_shot != nullptr && t_trial > 0.6) {
      QVERIFY(w.grab().save(QString::fromLatin1(mid_shot)));
      mid_shot = nullptr;
    }
    QTest::qWait(8);
  }
  if (down) sendMouse(view, QEvent::MouseButtonRelease, at(10.0), Qt::LeftButton, Qt::NoButton);
}

}  // namespace hattr::studio::test
