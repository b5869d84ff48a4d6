#include "ui/profile_plot.hpp"

#include <QPainter>
#include <QPainterPath>
#include <algorithm>
#include <cmath>

namespace hattr::studio {
namespace {

const QColor kAxisColours[3] = {QColor(215, 50, 40), QColor(30, 150, 60), QColor(40, 90, 215)};

/// A "nice" tick step (1, 2 or 5 times a power of ten) for about `count` ticks over `span`.
double niceStep(double span, int count) {
  const double raw = span / std::max(count, 1);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * magnitude >= raw) return m * magnitude;
  }
  return 10.0 * magnitude;
}

/// The plot's area in the widget [px] and the ranges of its axes: time [s], force [N].
struct PlotAxes {
  QRectF area;
  double t0 = 0.0, t1 = 1.0;
  double f0 = 0.0, f1 = 0.0;

  /// Where (t [s], f [N]) lies in the widget [px].
  [[nodiscard]] QPointF toPx(double t, double f) const {
    return QPointF(area.left() + (t - t0) / (t1 - t0) * area.width(),
                   area.bottom() - (f - f0) / (f1 - f0) * area.height());
  }
};

/// Axes' ranges: time from the window or the data; force from the data, at least ±0.5 N.
PlotAxes plotAxes(const QRectF& area, const std::optional<std::pair<double, double>>& window,
                  const ForceSeries& expert, const ForceSeries& trainee) {
  double t0 = 0.0, t1 = 1.0;
  if (window) {
    std::tie(t0, t1) = *window;
  } else if (!expert.empty() || !trainee.empty()) {
    t0 = std::numeric_limits<double>::infinity();
    t1 = -t0;
    for (const ForceSeries* s : {&expert, &trainee}) {
      if (s->empty()) continue;
      t0 = std::min(t0, s->t_s.front());
      t1 = std::max(t1, s->t_s.back());
    }
  }
  if (!(t1 > t0)) t1 = t0 + 1.0;
  auto [f0, f1] = expert.forceRange();
  const auto [g0, g1] = trainee.forceRange();
  f0 = std::min({f0, g0, -0.5});
  f1 = std::max({f1, g1, 0.5});
  const double pad = 0.08 * (f1 - f0);
  f0 -= pad;
  f1 += pad;
  return PlotAxes{area, t0, t1, f0, f1};
}

/// Grid, ticks and labels, in `font` a little smaller (kept by the painter for what follows).
void drawGrid(QPainter& painter, const PlotAxes& axes, const QFont& font) {
  const QRectF& area = axes.area;
  painter.setPen(QColor(70, 70, 70));
  QFont small = font;
  small.setPointSizeF(small.pointSizeF() * 0.85);
  painter.setFont(small);
  const double t_step = niceStep(axes.t1 - axes.t0, 8);
  for (double t = std::ceil(axes.t0 / t_step) * t_step; t <= axes.t1 + 1e-9; t += t_step) {
    const QPointF p = axes.toPx(t, axes.f0);
    painter.setPen(QColor(232, 232, 232));
    painter.drawLine(QPointF(p.x(), area.top()), QPointF(p.x(), area.bottom()));
    painter.setPen(QColor(70, 70, 70));
    painter.drawText(QRectF(p.x() - 30.0, area.bottom() + 2.0, 60.0, 14.0), Qt::AlignCenter,
                     QString::number(t, 'g', 4));
  }
  const double f_step = niceStep(axes.f1 - axes.f0, 5);
  for (double f = std::ceil(axes.f0 / f_step) * f_step; f <= axes.f1 + 1e-9; f += f_step) {
    const QPointF p = axes.toPx(axes.t0, f);
    painter.setPen(std::abs(f) < 1e-9 ? QColor(180, 180, 180) : QColor(232, 232, 232));
    painter.drawLine(QPointF(area.left(), p.y()), QPointF(area.right(), p.y()));
    painter.setPen(QColor(70, 70, 70));
    painter.drawText(QRectF(0.0, p.y() - 7.0, area.left() - 4.0, 14.0), Qt::AlignRight | Qt::AlignVCenter,
                     QString::number(f, 'g', 3));
  }
  painter.setPen(QColor(120, 120, 120));
  painter.drawRect(area);
  painter.drawText(QRectF(area.left(), area.bottom() + 16.0, area.width(), 14.0), Qt::AlignCenter,
                   ProfilePlot::tr("time [s]"));
  painter.save();
  painter.translate(12.0, area.center().y());
  painter.rotate(-90.0);
  painter.drawText(QRectF(-60.0, -8.0, 120.0, 16.0), Qt::AlignCenter, ProfilePlot::tr("force [N]"));
  painter.restore();
}

/// One series, a line per axis in the axis's colour, in `style` and `width_px`.
void drawSeries(QPainter& painter, const PlotAxes& axes, const ForceSeries& s, Qt::PenStyle style,
                double width_px) {
  const std::vector<double>* channels[3] = {&s.fx_N, &s.fy_N, &s.fz_N};
  for (int c = 0; c < 3; ++c) {
    if (s.empty()) continue;
    QPolygonF line;
    line.reserve(static_cast<qsizetype>(s.size()));
    for (std::size_t i = 0; i < s.size(); ++i) line << axes.toPx(s.t_s[i], (*channels[c])[i]);
    painter.setPen(QPen(kAxisColours[c], width_px, style));
    painter.drawPolyline(line);
  }
}

/// Title and legend above the plot's area.
void drawTitleAndLegend(QPainter& painter, const QRectF& area, const QString& title) {
  painter.setPen(QColor(40, 40, 40));
  painter.drawText(QRectF(area.left(), 3.0, area.width() * 0.5, 16.0), Qt::AlignLeft | Qt::AlignVCenter, title);
  const char* names[3] = {"fx", "fy", "fz"};
  for (int c = 0; c < 3; ++c) {
    const double x = area.right() - 150.0 + 50.0 * c;
    painter.setPen(QPen(kAxisColours[c], 2.0));
    painter.drawLine(QPointF(x, 11.0), QPointF(x + 14.0, 11.0));
    painter.setPen(QColor(40, 40, 40));
    painter.drawText(QPointF(x + 18.0, 15.0), QString::fromLatin1(names[c]));
  }
  painter.setPen(QColor(90, 90, 90));
  painter.drawText(QRectF(area.left() + area.width() * 0.5, 3.0, area.width() * 0.5 - 160.0, 16.0),
                   Qt::AlignRight | Qt::AlignVCenter, ProfilePlot::tr("dashed: expert · solid: you"));
}

}  // namespace

ProfilePlot::ProfilePlot(QWidget* parent) : QWidget(parent) { setMinimumHeight(150); }

void ProfilePlot::clear() {
  expert_.clear();
  trainee_.clear();
  cursor_t_s_.reset();
  update();
}

void ProfilePlot::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.fillRect(rect(), Qt::white);
  const QRectF area(52.0, 22.0, width() - 64.0, height() - 50.0);
  if (area.width() < 20.0 || area.height() < 20.0) return;

  // Axes' ranges: time from the window or the data; force from the data, at least ±0.5 N.
  const PlotAxes axes = plotAxes(area, window_, expert_, trainee_);

  // Grid, ticks and labels.
  drawGrid(painter, axes, font());

  // The series: expert dashed, trainee solid.
  painter.setClipRect(area);
  drawSeries(painter, axes, expert_, Qt::DashLine, 1.2);
  drawSeries(painter, axes, trainee_, Qt::SolidLine, 1.8);
  if (cursor_t_s_) {
    painter.setPen(QPen(QColor(0, 0, 0, 140), 1.0));
    const QPointF p = axes.toPx(*cursor_t_s_, axes.f0);
    painter.drawLine(QPointF(p.x(), area.top()), QPointF(p.x(), area.bottom()));
  }
  painter.setClipping(false);

  // Title and legend.
  drawTitleAndLegend(painter, area, title_);
}

}  // namespace hattr::studio
