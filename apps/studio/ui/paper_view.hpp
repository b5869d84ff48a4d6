#pragma once
/// The paper seen from above: the paper's grain (the relief of the world configuration,
/// cached as an image), the expert's reference when the phase shows it, the pen's trail, a
/// trial overlaid for review, the pen with the user's force and the guidance force as arrows
/// in the paper plane, and a banner for prompts and countdowns. The mouse over the view is
/// the hand holding the simulated pen: the cursor is the hand's target, the left button puts
/// the pen down, the wheel sets how hard the hand presses. Millimetres only in the labels.

#include <QFont>
#include <QImage>
#include <QRectF>
#include <QString>
#include <QWidget>
#include <limits>
#include <optional>
#include <vector>

#include "core/mouse_hand.hpp"
#include "core/paper_mapping.hpp"
#include "core/series.hpp"
#include "core/tablet_input.hpp"
#include "hattr/core/sample.hpp"
#include "hattr/render/height_field.hpp"

namespace hattr::studio {

/// The colours of the view (also what the smoke test looks for).
struct PaperColours {
  static QColor reference() { return {40, 110, 230}; }  ///< the expert's path
  static QColor ink() { return {20, 20, 35}; }          ///< the pen's trail
  static QColor overlay() { return {225, 70, 20}; }     ///< a reviewed trial
  static QColor userForce() { return {235, 120, 0}; }   ///< the user's force on the paper
  static QColor guideForce() { return {0, 165, 70}; }   ///< the guidance force on the pen
  static QColor peer() { return {165, 30, 200}; }       ///< the other station's pen (Mentor tab)
  static QColor barrel() { return {70, 80, 100}; }      ///< the pen's barrel (3-D view)
};

class PaperView final : public QWidget {
  Q_OBJECT

 public:
  explicit PaperView(QWidget* parent = nullptr);

  /// The hand the mouse drives (may be null: the mouse does nothing).
  void setMouseHand(MouseHand* hand) { hand_ = hand; }
  /// The paper's relief and the rectangle of the paper shown [m]; rebuilds the cached image.
  void setPaper(const render::HeightField& relief, double x_min_m, double y_min_m, double x_max_m, double y_max_m);

  /// The pen as the loop last published it (nullopt: no pen drawn).
  void setPen(const std::optional<Sample>& pen) { pen_ = pen; }
  [[nodiscard]] const std::optional<Sample>& pen() const { return pen_; }
  /// The expert's reference path (drawn when shown).
  Trail& reference() { return reference_; }
  [[nodiscard]] const Trail& reference() const { return reference_; }
  void setReferenceShown(bool shown) { reference_shown_ = shown; }
  [[nodiscard]] bool referenceShown() const { return reference_shown_; }
  /// Where the reference is now (a marker), or nothing.
  void setReferenceCue(const std::optional<Eigen::Vector2d>& cue_m) { cue_m_ = cue_m; }
  /// The pen's trail (live, or a replayed take).
  Trail& trail() { return trail_; }
  [[nodiscard]] const Trail& trail() const { return trail_; }
  /// A trial overlaid on the reference (review).
  Trail& overlay() { return overlay_; }
  [[nodiscard]] const Trail& overlay() const { return overlay_; }
  /// The other station's pen in a mentored session and its trail, drawn in PaperColours::peer()
  /// with `label` beside the pen (null trail: none; the trail must outlive its use here).
  void setPeer(const Trail* trail, const std::optional<Sample>& pen, const QString& label = {}) {
    peer_trail_ = trail;
    peer_pen_ = pen;
    peer_label_ = label;
  }
  /// Text over the paper (prompts, countdowns); empty: none.
  void setBanner(const QString& text) { banner_ = text; }
  [[nodiscard]] const QString& banner() const { return banner_; }
  /// Where and how the banner is drawn: a box over the paper's top, 0.7 of its width, in the
  /// view's font bold at 1.6 times its size, smaller (down to its own size) until the text fits
  /// the box on at most two lines. `fits` false: even that did not fit (the text is cut).
  struct BannerLayout {
    QRectF box;
    QFont font;
    bool fits = false;
  };
  [[nodiscard]] BannerLayout bannerLayout() const;
  void setForceArrowsShown(bool shown) { arrows_shown_ = shown; }
  /// How much of the paper is shown: all of it (1), or its middle half (2), third (3) or quarter
  /// (4), larger on the screen: letters are 10 to 20 mm tall. The mouse's hand moves over the
  /// part shown, so a zoom also makes the hand's strokes finer. Clamped to 1..kMaxZoom.
  void setZoom(int zoom);
  [[nodiscard]] int zoom() const { return zoom_; }
  static constexpr int kMaxZoom = 4;
  /// A letter to trace (the Record tab's guide): its strokes in the paper plane [m], drawn wide
  /// and faint under everything else, each stroke's start numbered in writing order and its
  /// direction arrowed (empty: none).
  void setLetterGuide(std::vector<std::vector<Eigen::Vector2d>> strokes_m) {
    guide_m_ = std::move(strokes_m);
    update();
  }
  [[nodiscard]] const std::vector<std::vector<Eigen::Vector2d>>& letterGuide() const { return guide_m_; }
  /// The guide's colour.
  [[nodiscard]] static QColor guideColour() { return {196, 202, 226}; }
  /// The largest force the pen renders [N] (its continuous force, which the safety path clamps
  /// the total to): the guidance arrow is drawn no longer, marked where the guidance asks more.
  void setForceLimit(double force_N) { force_limit_N_ = force_N; }
  /// Engineering read-outs (pen z, fz, guidance) or plain ones (how high, how hard, the help).
  void setEngineerView(bool on) { engineer_view_ = on; }
  /// The read-out line as it is drawn now (for tests and screen readers).
  [[nodiscard]] QString readout() const;

  [[nodiscard]] const PaperMapping& mapping() const { return mapping_; }

  /// How a pen tablet's pressure becomes the hand's press force (defaultTabletCalibration()).
  void setTabletCalibration(const io::TabletCalibration& calibration) { tablet_calibration_ = calibration; }
  [[nodiscard]] const io::TabletCalibration& tabletCalibration() const { return tablet_calibration_; }

 signals:
  /// The wheel changed the press force [N].
  void pressChanged(double press_N);

 protected:
  void paintEvent(QPaintEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;
  /// A pen tablet: position as the mouse's, pressure → press force through the tablet
  /// calibration, tilt → pen angles. Accepted, so Qt synthesizes no mouse events.
  void tabletEvent(QTabletEvent* event) override;

 private:
  void publish(const QPointF& px, std::optional<bool> pen_down);
  void drawTrail(QPainter& painter, const Trail& trail, const QColor& colour, double width_px) const;
  /// An arrow of `f_N` at 10 mm a newton, no longer than `cap_N` (two bars across it where capped).
  void drawArrow(QPainter& painter, const QPointF& from, const Eigen::Vector2d& f_N, const QColor& colour,
                 double cap_N = std::numeric_limits<double>::infinity()) const;
  void drawPeerPen(QPainter& painter) const;
  void drawPaper(QPainter& painter, const QRectF& paper) const;
  void drawPen(QPainter& painter) const;
  void drawLetterGuide(QPainter& painter) const;
  [[nodiscard]] QRectF reliefSourceRect() const;
  void drawReadouts(QPainter& painter, const QRectF& paper) const;
  void drawLegend(QPainter& painter, const QRectF& paper) const;
  void drawBanner(QPainter& painter) const;

  MouseHand* hand_ = nullptr;
  PaperMapping mapping_;
  io::TabletCalibration tablet_calibration_ = defaultTabletCalibration();
  QImage relief_image_;
  std::optional<Sample> pen_;
  Trail reference_;
  Trail trail_;
  Trail overlay_;
  bool reference_shown_ = true;
  bool arrows_shown_ = true;
  double force_limit_N_ = 1.75;
  bool engineer_view_ = false;
  std::vector<std::vector<Eigen::Vector2d>> guide_m_;
  QRectF full_paper_{QPointF(-0.08, -0.06), QPointF(0.08, 0.06)};  // the whole paper in W [m]
  int zoom_ = 1;
  std::optional<Eigen::Vector2d> cue_m_;
  const Trail* peer_trail_ = nullptr;
  std::optional<Sample> peer_pen_;
  QString peer_label_;
  QString banner_;
};

}  // namespace hattr::studio
