#include "ui/learning_curve.hpp"

#include <QPainter>
#include <QPainterPath>
#include <algorithm>
#include <cmath>

namespace hattr::studio {

LearningCurve::LearningCurve(QWidget* parent) : QWidget(parent) {
  setSizePolicy(QSizePolicy::Preferred, QSizePolicy::Fixed);
  setMinimumHeight(minimumSizeHint().height());
  setToolTip(tr("Your training trials' scores against this reference, in order; lower is closer. "
                "Each point in its strategy's colour: grey BASIC, blue PCONTROL, green ALPHA, ..."));
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

  // Two panels, shape above force, each with its name and its largest score at the left.
  const int label_w = metrics.horizontalAdvance(QStringLiteral("Force 00.00")) + 6;
  const int panel_h = (height() - 4) / 2;
  const auto panel = [&](int row, const QString& name, auto value) {
    const QRectF area(label_w, 2 + row * panel_h + 4, width() - label_w - 8, panel_h - 8);
    double largest = 0.0;
    for (const Point& p : points_) {
      if (std::isfinite(value(p))) largest = std::max(largest, value(p));
    }
    const double top = largest > 0.0 ? largest * 1.1 : 1.0;
    painter.setPen(palette().color(QPalette::Text));
    painter.drawText(QRectF(2, area.top(), label_w - 6, area.height()), Qt::AlignLeft | Qt::AlignVCenter,
                     QStringLiteral("%1\n%2").arg(name).arg(largest, 0, 'g', 3));
    painter.setPen(palette().color(QPalette::Mid));
    painter.setBrush(Qt::NoBrush);
    painter.drawRect(area);
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
  };
  panel(0, tr("Shape"), [](const Point& p) { return p.shape; });
  panel(1, tr("Force"), [](const Point& p) { return p.force; });
}

}  // namespace hattr::studio
