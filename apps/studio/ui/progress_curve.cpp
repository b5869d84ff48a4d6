#include "ui/progress_curve.hpp"

#include <QPainter>
#include <QPainterPath>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>

namespace hattr::studio {
namespace {

const QColor kGuided(143, 179, 217);
const QColor kAlone(31, 78, 121);
const QColor kBest(212, 160, 23);
const QColor kLatest(192, 57, 43);

}  // namespace

ProgressCurve::ProgressCurve(QWidget* parent) : QWidget(parent) {
  setObjectName("progress_curve");
  setToolTip(tr("Each letter's shape, in the order written: lower is closer to the model letter. Light: guided; "
                "dark: written alone; ringed: the best and the latest written alone."));
}

void ProgressCurve::setTrials(std::vector<report::ProgressTrial> trials, bool compares_alone) {
  trials_ = std::move(trials);
  compares_alone_ = compares_alone;
  update();
}

// The legend, in a row above the plot, from `x`.
void ProgressCurve::drawLegend(QPainter& painter, double x) {
  const QFontMetrics metrics(font());
  const int line_h = metrics.height();
  const auto key = [&](const QColor& colour, bool ring, const QString& text) {
    const QPointF centre(x + 5, 4 + line_h / 2.0);
    painter.setPen(ring ? QPen(colour, 2.0) : Qt::NoPen);
    painter.setBrush(ring ? QBrush(Qt::NoBrush) : QBrush(colour));
    painter.drawEllipse(centre, ring ? 5.0 : 3.5, ring ? 5.0 : 3.5);
    painter.setPen(palette().color(QPalette::Text));
    painter.drawText(QPointF(x + 13, 4 + metrics.ascent()), text);
    x += 13 + metrics.horizontalAdvance(text) + 14;
  };
  if (compares_alone_) key(kGuided, false, tr("guided"));
  key(kAlone, false, compares_alone_ ? tr("written alone") : tr("guided"));
  key(kBest, true, tr("best"));
  key(kLatest, true, tr("latest"));
}

void ProgressCurve::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.fillRect(rect(), palette().base());
  if (trials_.empty()) {
    painter.setPen(palette().color(QPalette::PlaceholderText));
    painter.drawText(rect(), Qt::AlignCenter | Qt::TextWordWrap, tr("The learner's letters will show here."));
    return;
  }
  // The legend above, the y numbers at the left, the trial numbers below.
  const QFontMetrics metrics(font());
  const int line_h = metrics.height();
  // Room for the latest ring (radius 9.5) inside the widget at either end.
  const double left = metrics.horizontalAdvance(QStringLiteral("0000")) + 12;
  const QRectF area(left, line_h + 14, width() - left - 14, height() - 2 * line_h - 22);
  double largest = 0.0;
  for (const auto& t : trials_) {
    if (std::isfinite(t.shape)) largest = std::max(largest, t.shape);
  }
  const double top = largest > 0.0 ? largest * 1.1 : 1.0;
  const int last = trials_.back().number;
  const auto at = [&](const report::ProgressTrial& t) {
    const double x = last <= 1 ? area.center().x() : area.left() + area.width() * (t.number - 1) / (last - 1);
    return QPointF(x, area.bottom() - area.height() * t.shape / top);
  };

  painter.setPen(palette().color(QPalette::Mid));
  painter.drawRect(area);
  painter.setPen(palette().color(QPalette::Text));
  painter.drawText(QRectF(0, area.top() - line_h / 2.0, area.left() - 4, line_h), Qt::AlignRight,
                   QString::number(top, 'f', 0));
  painter.drawText(QRectF(0, area.bottom() - line_h / 2.0, area.left() - 4, line_h), Qt::AlignRight, QStringLiteral("0"));
  painter.drawText(QRectF(area.left() - 20, area.bottom() + 2, 40, line_h), Qt::AlignHCenter, QStringLiteral("1"));
  painter.drawText(QRectF(area.right() - 40, area.bottom() + 2, 80, line_h), Qt::AlignHCenter, QString::number(last));
  painter.drawText(QRectF(area.left(), area.bottom() + 2, area.width(), line_h), Qt::AlignHCenter,
                   tr("trial (lower is closer to the model)"));

  // The compared trials joined in order, letter by letter; then every point; then the rings.
  const auto light = [&](const report::ProgressTrial& t) { return t.guided && compares_alone_; };
  std::map<std::string, QPainterPath> by_letter;
  for (const auto& t : trials_) {
    if (light(t) || !std::isfinite(t.shape)) continue;
    QPainterPath& line = by_letter[t.skill];
    if (line.elementCount() == 0) {
      line.moveTo(at(t));
    } else {
      line.lineTo(at(t));
    }
  }
  painter.setPen(QPen(kAlone, 1.2));
  painter.setBrush(Qt::NoBrush);
  for (const auto& [letter, line] : by_letter) painter.drawPath(line);
  painter.setPen(Qt::NoPen);
  for (const auto& t : trials_) {
    if (!std::isfinite(t.shape)) continue;
    painter.setBrush(light(t) ? kGuided : kAlone);
    painter.drawEllipse(at(t), 3.5, 3.5);
  }
  painter.setBrush(Qt::NoBrush);
  for (const auto& t : trials_) {
    if (!std::isfinite(t.shape)) continue;
    if (t.best) {
      painter.setPen(QPen(kBest, 2.5));
      painter.drawEllipse(at(t), 7.0, 7.0);
    }
    if (t.latest) {
      painter.setPen(QPen(kLatest, 2.0));
      painter.drawEllipse(at(t), 9.5, 9.5);
    }
  }

  drawLegend(painter, area.left());
}

}  // namespace hattr::studio
