#pragma once
/// A small plot of the haptic profile: the user's force on the paper (fx, fy, fz [N]) over
/// time [s], the expert's dashed beside the trainee's solid, one colour per axis. Drawn
/// with QPainter; GUI thread only.

#include <QString>
#include <QWidget>
#include <optional>

#include "core/series.hpp"

namespace hattr::studio {

class ProfilePlot final : public QWidget {
  Q_OBJECT

 public:
  explicit ProfilePlot(QWidget* parent = nullptr);

  /// The expert's forces (dashed); empty: none.
  void setExpert(ForceSeries series) {
    expert_ = std::move(series);
    update();
  }
  [[nodiscard]] const ForceSeries& expert() const { return expert_; }
  /// The trainee's forces (solid), appended live or set at once.
  ForceSeries& trainee() { return trainee_; }
  void setTrainee(ForceSeries series) {
    trainee_ = std::move(series);
    update();
  }
  /// The time axis [s]; nullopt: the span of the data.
  void setTimeWindow(std::optional<std::pair<double, double>> window) {
    window_ = window;
    update();
  }
  /// A vertical line at time t [s] (playback); nullopt: none.
  void setCursorTime(std::optional<double> t_s) {
    cursor_t_s_ = t_s;
    update();
  }
  void setTitle(const QString& title) {
    title_ = title;
    update();
  }
  void clear();

  [[nodiscard]] QSize sizeHint() const override { return {640, 190}; }

 protected:
  void paintEvent(QPaintEvent* event) override;

 private:
  ForceSeries expert_;
  ForceSeries trainee_;
  std::optional<std::pair<double, double>> window_;
  std::optional<double> cursor_t_s_;
  QString title_;
};

}  // namespace hattr::studio
