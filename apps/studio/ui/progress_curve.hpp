#pragma once
/// The Learners tab's learning curve of one learner's plan: every trial's shape cost in the
/// order written (x: trial number), guided trials light, the compared ones (written alone, or
/// every trial of a plan that is all guided) dark and joined letter by letter, the best and the
/// latest ringed, with a legend and the axes' numbers. Lower is closer to the model letter.
/// GUI thread only.

#include <QPainter>
#include <QWidget>
#include <vector>

#include "hattr/report/learner_progress.hpp"

namespace hattr::studio {

class ProgressCurve final : public QWidget {
  Q_OBJECT

 public:
  explicit ProgressCurve(QWidget* parent = nullptr);
  /// `compares_alone`: report::LearnerProgress::compares_alone.
  void setTrials(std::vector<report::ProgressTrial> trials, bool compares_alone = true);
  [[nodiscard]] const std::vector<report::ProgressTrial>& trials() const { return trials_; }
  [[nodiscard]] QSize sizeHint() const override { return {420, 200}; }
  [[nodiscard]] QSize minimumSizeHint() const override { return {240, 150}; }

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  void drawLegend(QPainter& painter, double x);
  std::vector<report::ProgressTrial> trials_;
  bool compares_alone_ = true;
};

}  // namespace hattr::studio
