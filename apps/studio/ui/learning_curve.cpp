#include "ui/learning_curve.hpp"

#include <QPainter>
#include <QPainterPath>
#include <algorithm>
#include <cmath>
#include <vector>

#include "hattr/guidance/strategy_catalog.hpp"
#include "ui/ui_text.hpp"

namespace hattr::studio {

LearningCurve::LearningCurve(QWidget* parent) : QWidget(parent) {
  setSizePolicy(QSizePolicy::Preferred, QSizePolicy::Fixed);
  setMinimumHeight(minimumSizeHint().height());
  setToolTip(tr("Your training trials' scores against this reference, in order; lower is closer. "
                "Each point in its strategy's colour (the legend on top); at the left, the latest trial's scores."));
}

void LearningCurve::add(guidance::TrainingMode mode, const analysis::TrialScore& score) {
  points_.push_back({mode, score.shape(), score.force()});
  update();
}

void LearningCurve::clear() {
  points_.clear();
  update();
}

QColor LearningCurve::modeColour(guidance::TrainingMode mode) {
  switch (mode) {
    case guidance::TrainingMode::kPositionControl: return {40, 110, 230};
    case guidance::TrainingMode::kForceControl: return {0, 150, 70};
    case guidance::TrainingMode::kChannel: return {0, 150, 170};
    case guidance::TrainingMode::kErrorAugmentation: return {200, 60, 40};
    case guidance::TrainingMode::kNoise: return {150, 90, 30};
    case guidance::TrainingMode::kPlayback: return {140, 60, 170};
    case guidance::TrainingMode::kFading: return {120, 160, 240};
    case guidance::TrainingMode::kAssistAsNeeded: return {230, 140, 0};
    case guidance::TrainingMode::kPartialThenFull: return {90, 120, 40};
    default: return {110, 110, 110};
  }
}

// The legend of the strategies on the curve, in a row at the top: a dot in each one's colour.
void LearningCurve::drawLegend(QPainter& painter, int line_h) {
  std::vector<guidance::TrainingMode> modes;
  for (const Point& p : points_) {
    if (std::find(modes.begin(), modes.end(), p.mode) == modes.end()) modes.push_back(p.mode);
  }
  const QFontMetrics metrics(font());
  double x = 4.0;
  for (const auto mode : modes) {
    const QString name = qs(guidance::strategyInfo(mode).plain_name);
    painter.setPen(Qt::NoPen);
    painter.setBrush(modeColour(mode));
    painter.drawEllipse(QPointF(x + 4.0, 2.0 + line_h / 2.0), 3.5, 3.5);
    painter.setPen(palette().color(QPalette::Text));
    painter.drawText(QPointF(x + 11.0, 2.0 + metrics.ascent()), name);
    x += 11.0 + metrics.horizontalAdvance(name) + 10.0;
  }
}

void LearningCurve::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.fillRect(rect(), palette().base());
  const QFontMetrics metrics(font());
  if (points_.empty()) {
    painter.setPen(palette().color(QPalette::PlaceholderText));
    painter.drawText(rect(), Qt::AlignCenter | Qt::TextWordWrap, tr("Your training scores will show here."));
    return;
  }

  // The legend on top; two panels, shape above force, each with its name and its latest score
  // at the left and its top value inside its corner; the trial numbers under the lower one.
  const int line_h = metrics.height();
  drawLegend(painter, line_h);
  const int label_w = metrics.horizontalAdvance(QStringLiteral("latest 000.0")) + 6;
  const double top_y = line_h + 4.0;
  const double panel_h = (height() - top_y - line_h - 4.0) / 2.0;
  const auto panel = [&](int row, const QString& name, auto value) {
    const QRectF area(label_w, top_y + row * panel_h + 3, width() - label_w - 8, panel_h - 6);
    double largest = 0.0;
    for (const Point& p : points_) {
      if (std::isfinite(value(p))) largest = std::max(largest, value(p));
    }
    const double top = largest > 0.0 ? largest * 1.1 : 1.0;
    painter.setPen(palette().color(QPalette::Text));
    painter.drawText(QRectF(2, area.top(), label_w - 6, area.height()), Qt::AlignLeft | Qt::AlignVCenter,
                     tr("%1\nlatest %2").arg(name).arg(value(points_.back()), 0, 'f', 1));
    painter.setPen(palette().color(QPalette::Mid));
    painter.setBrush(Qt::NoBrush);
    painter.drawRect(area);
    painter.drawText(area.adjusted(3, 1, -3, -1), Qt::AlignRight | Qt::AlignTop, QString::number(top, 'f', 0));
    // x: trial 1 at the left edge, the last at the right (one trial: the middle).
    // A score that is not a number (a trial the scorer could not take) is left out.
    const auto at = [&](std::size_t i) {
      const double x = points_.size() == 1 ? area.center().x()
                                           : area.left() + area.width() * static_cast<double>(i) /
                                                               static_cast<double>(points_.size() - 1);
      return QPointF(x, area.bottom() - area.height() * value(points_[i]) / top);
    };
    QPainterPath line;
    for (std::size_t i = 0; i < points_.size(); ++i) {
      if (!std::isfinite(value(points_[i]))) continue;
      if (line.elementCount() == 0) {
        line.moveTo(at(i));
      } else {
        line.lineTo(at(i));
      }
    }
    painter.setPen(QPen(palette().color(QPalette::Mid), 1.0));
    painter.drawPath(line);
    painter.setPen(Qt::NoPen);
    for (std::size_t i = 0; i < points_.size(); ++i) {
      if (!std::isfinite(value(points_[i]))) continue;
      painter.setBrush(modeColour(points_[i].mode));
      painter.drawEllipse(at(i), 3.5, 3.5);
    }
    return area;
  };
  panel(0, tr("Shape"), [](const Point& p) { return p.shape; });
  const QRectF lower = panel(1, tr("Force"), [](const Point& p) { return p.force; });
  painter.setPen(palette().color(QPalette::Text));
  const QRectF numbers(lower.left(), lower.bottom() + 1, lower.width(), line_h);
  painter.drawText(numbers, Qt::AlignLeft | Qt::AlignTop, tr("trial 1"));
  if (points_.size() > 1) painter.drawText(numbers, Qt::AlignRight | Qt::AlignTop, QString::number(points_.size()));
}

}  // namespace hattr::studio
