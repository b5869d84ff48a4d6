#pragma once
/// The Train tab's learning curve: the shape and force scores of this session's training
/// trials against the current reference, trial by trial, each point in its mode's colour (a
/// legend of the strategies on top). Two small panels, one a metric, each from 0 to just above
/// its largest score (the top value in its corner), the latest scores at the left, the trial
/// numbers under them (lower is closer).
/// A new reference starts a new curve: scores against another expert do not compare.

#include <QPainter>
#include <QWidget>
#include <vector>

#include "hattr/analysis/trial_score.hpp"
#include "hattr/guidance/training_guidance.hpp"

namespace hattr::studio {

class LearningCurve final : public QWidget {
  Q_OBJECT

 public:
  /// One training trial's scores.
  struct Point {
    guidance::TrainingMode mode = guidance::TrainingMode::kBasic;
    double shape = 0.0;  ///< DTW x + y
    double force = 0.0;  ///< DTW fx + fy + fz
  };

  explicit LearningCurve(QWidget* parent = nullptr);

  void add(guidance::TrainingMode mode, const analysis::TrialScore& score);
  void clear();
  [[nodiscard]] const std::vector<Point>& points() const { return points_; }
  /// The colour a mode's points are drawn in.
  [[nodiscard]] static QColor modeColour(guidance::TrainingMode mode);

  [[nodiscard]] QSize sizeHint() const override { return {260, 170}; }
  [[nodiscard]] QSize minimumSizeHint() const override { return {160, 150}; }

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  void drawLegend(QPainter& painter, int line_h);
  std::vector<Point> points_;
};

}  // namespace hattr::studio
