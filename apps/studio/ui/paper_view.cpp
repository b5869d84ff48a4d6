#include "ui/paper_view.hpp"

#include <QFontInfo>
#include <QFontMetricsF>
#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <QTabletEvent>
#include <QWheelEvent>
#include <cmath>
#include <vector>

#include "core/relief_image.hpp"
#include "ui/trail_drawing.hpp"

namespace hattr::studio {
namespace {

constexpr double kReliefPixelsPerMetre = 6000.0;  // cached relief: 6 px/mm
constexpr double kArrowMetresPerNewton = 0.01;    // force arrows: 10 mm of paper per newton
constexpr double kPenRadius_px = 6.0;
/// Room between the banner's box and its text, left and right.
constexpr double kBannerMargin_px = 8.0;

}  // namespace

PaperView::PaperView(QWidget* parent) : QWidget(parent) {
  setMouseTracking(true);
  setMinimumSize(400, 300);  // 2.5 px a millimetre: with the 3-D view and seven tabs, 1024 px still fit
  setFocusPolicy(Qt::StrongFocus);
  setCursor(Qt::CrossCursor);
  mapping_.setWidgetSize(width(), height());
}

void PaperView::setPaper(const render::HeightField& relief, double x_min_m, double y_min_m, double x_max_m,
                         double y_max_m) {
  full_paper_ = QRectF(QPointF(x_min_m, y_min_m), QPointF(x_max_m, y_max_m));
  const int w = static_cast<int>(std::lround((x_max_m - x_min_m) * kReliefPixelsPerMetre));
  const int h = static_cast<int>(std::lround((y_max_m - y_min_m) * kReliefPixelsPerMetre));
  relief_image_ = reliefImage(relief, x_min_m, y_min_m, x_max_m, y_max_m, w, h);
  setZoom(zoom_);
}

void PaperView::setZoom(int zoom) {
  zoom_ = std::clamp(zoom, 1, kMaxZoom);
  // The middle of the paper, 1/zoom of it each way.
  const QPointF centre = full_paper_.center();
  const QSizeF half = full_paper_.size() / (2.0 * zoom_);
  mapping_.setPaperRect(centre.x() - half.width(), centre.y() - half.height(), centre.x() + half.width(),
                        centre.y() + half.height());
  update();
}

QRectF PaperView::reliefSourceRect() const {
  // The shown part of the paper in the relief image's pixels (its row 0 is the paper's far edge).
  const double sx = relief_image_.width() / full_paper_.width(), sy = relief_image_.height() / full_paper_.height();
  return QRectF((mapping_.xMin() - full_paper_.left()) * sx, (full_paper_.bottom() - mapping_.yMax()) * sy,
                (mapping_.xMax() - mapping_.xMin()) * sx, (mapping_.yMax() - mapping_.yMin()) * sy);
}

void PaperView::resizeEvent(QResizeEvent* event) {
  QWidget::resizeEvent(event);
  mapping_.setWidgetSize(width(), height(), 10);
}

// ---- Mouse: the hand ---------------------------------------------------------------------

void PaperView::publish(const QPointF& px, std::optional<bool> pen_down) {
  if (hand_ == nullptr) return;
  MouseInput input = hand_->input();
  const Eigen::Vector2d p = mapping_.clampToPaper(mapping_.toPaper(px));
  input.x_m = p.x();
  input.y_m = p.y();
  input.tablet = false;  // the mouse moved: it is the hand again
  if (pen_down) input.pen_down = *pen_down;
  hand_->setInput(input);
}

void PaperView::tabletEvent(QTabletEvent* event) {
  event->accept();
  if (hand_ == nullptr) return;
  MouseInput input = hand_->input();
  const Eigen::Vector2d p = mapping_.clampToPaper(mapping_.toPaper(event->position()));
  input.x_m = p.x();
  input.y_m = p.y();
  input.tablet = true;
  if (event->type() == QEvent::TabletPress) input.pen_down = true;
  if (event->type() == QEvent::TabletRelease) input.pen_down = false;
  input.tablet_press_N = tabletPressureToNewtons(event->pressure(), tablet_calibration_);
  const PenAngles angles = penAnglesFromTilt(event->xTilt(), event->yTilt());
  input.altitude_rad = angles.altitude_rad;
  input.azimuth_rad = angles.azimuth_rad;
  hand_->setInput(input);
}

void PaperView::mouseMoveEvent(QMouseEvent* event) { publish(event->position(), std::nullopt); }

void PaperView::mousePressEvent(QMouseEvent* event) {
  if (event->button() == Qt::LeftButton) publish(event->position(), true);
}

void PaperView::mouseReleaseEvent(QMouseEvent* event) {
  if (event->button() == Qt::LeftButton) publish(event->position(), false);
}

void PaperView::wheelEvent(QWheelEvent* event) {
  if (hand_ == nullptr) return;
  MouseInput input = hand_->input();
  input.press_N = PressScale::afterWheel(input.press_N, event->angleDelta().y());
  hand_->setInput(input);
  emit pressChanged(input.press_N);
  event->accept();
}

// ---- Drawing -------------------------------------------------------------------------------

void PaperView::drawTrail(QPainter& painter, const Trail& trail, const QColor& colour, double width_px) const {
  drawTrailStrokes(painter, trail, colour, width_px,
                   [this](const Eigen::Vector2d& p) { return mapping_.toWidget(p.x(), p.y()); });
}

void PaperView::drawArrow(QPainter& painter, const QPointF& from, const Eigen::Vector2d& f_N, const QColor& colour,
                          double cap_N) const {
  const bool capped = f_N.norm() > cap_N;
  const double length_px = std::min(f_N.norm(), cap_N) * kArrowMetresPerNewton * mapping_.pixelsPerMetre();
  if (length_px < 2.0) return;
  // Screen y points down: the paper's +y is up.
  const QPointF direction(f_N.x() / f_N.norm(), -f_N.y() / f_N.norm());
  const QPointF tip = from + direction * length_px;
  const QPointF normal(-direction.y(), direction.x());
  const double head = std::min(9.0, 0.4 * length_px);
  painter.setPen(QPen(colour, 2.5, Qt::SolidLine, Qt::RoundCap));
  painter.drawLine(from, tip);
  painter.setBrush(colour);
  painter.drawPolygon(
      QPolygonF{tip, tip - direction * head + normal * head * 0.5, tip - direction * head - normal * head * 0.5});
  painter.setBrush(Qt::NoBrush);
  // Asked for more than the pen gives: two bars across the shaft before the head.
  if (capped) {
    for (const double back : {head + 3.0, head + 7.0}) {
      const QPointF at = tip - direction * back;
      painter.drawLine(at + normal * 5.0, at - normal * 5.0);
    }
  }
}

// The other station's pen: filled on the paper, a ring above it, its label beside it.
void PaperView::drawPeerPen(QPainter& painter) const {
  if (!peer_pen_) return;
  const QPointF at = mapping_.toWidget(peer_pen_->p_WT);
  if (peer_pen_->in_contact) {
    painter.setPen(QPen(Qt::white, 1.5));
    painter.setBrush(PaperColours::peer());
    painter.drawEllipse(at, kPenRadius_px, kPenRadius_px);
  } else {
    const double lift_px = std::clamp(peer_pen_->p_WT.z() * 1000.0, 0.0, 10.0) * 1.5;
    painter.setPen(QPen(PaperColours::peer(), 2.0));
    painter.setBrush(Qt::NoBrush);
    painter.drawEllipse(at, kPenRadius_px + lift_px, kPenRadius_px + lift_px);
  }
  painter.setBrush(Qt::NoBrush);
  if (!peer_label_.isEmpty()) {
    painter.setPen(PaperColours::peer());
    painter.drawText(at + QPointF(kPenRadius_px + 6.0, -kPenRadius_px - 4.0), peer_label_);
  }
}

// The desk and the paper with its grain; a scale bar of 10 mm.
void PaperView::drawPaper(QPainter& painter, const QRectF& paper) const {
  painter.fillRect(rect(), QColor(66, 70, 78));
  if (relief_image_.isNull()) {
    painter.fillRect(paper, paperColour());
  } else {
    painter.drawImage(paper, relief_image_, reliefSourceRect());
  }
  painter.setPen(QPen(QColor(160, 160, 150), 1.0));
  painter.drawRect(paper);
}

// The letter guide: each stroke a wide faint band, its start a numbered disc, an arrowhead a
// little way along it in the writing direction.
void PaperView::drawLetterGuide(QPainter& painter) const {
  const QColor numbers(80, 92, 150);
  QFont small = font();
  small.setBold(true);
  painter.setFont(small);
  for (std::size_t k = 0; k < guide_m_.size(); ++k) {
    const auto& stroke = guide_m_[k];
    if (stroke.size() < 2) continue;
    QPolygonF line;
    for (const auto& p : stroke) line << mapping_.toWidget(p.x(), p.y());
    painter.setPen(QPen(guideColour(), 9.0, Qt::SolidLine, Qt::RoundCap, Qt::RoundJoin));
    painter.drawPolyline(line);
    // The arrowhead between the second and third via point (or the first two).
    const std::size_t i = std::min<std::size_t>(1, line.size() - 2);
    const QPointF a = line[static_cast<int>(i)], b = line[static_cast<int>(i) + 1];
    const QPointF d = b - a;
    const double len = std::hypot(d.x(), d.y());
    if (len > 1.0) {
      const QPointF u = d / len, n(-u.y(), u.x()), tip = (a + b) / 2.0 + u * 4.0;
      painter.setPen(Qt::NoPen);
      painter.setBrush(numbers);
      painter.drawPolygon(QPolygonF{tip, tip - u * 8.0 + n * 4.5, tip - u * 8.0 - n * 4.5});
    }
    painter.setPen(Qt::NoPen);
    painter.setBrush(numbers);
    painter.drawEllipse(line.front(), 8.0, 8.0);
    painter.setPen(Qt::white);
    painter.drawText(QRectF(line.front() - QPointF(8.0, 8.0), QSizeF(16.0, 16.0)), Qt::AlignCenter,
                     QString::number(k + 1));
  }
  painter.setBrush(Qt::NoBrush);
  painter.setFont(font());
}

// The pen: filled on the paper, a ring growing with its height above it; its forces.
void PaperView::drawPen(QPainter& painter) const {
  if (!pen_) return;
  const QPointF at = mapping_.toWidget(pen_->p_WT);
  if (arrows_shown_) {
    drawArrow(painter, at, pen_->f_user_W.head<2>(), PaperColours::userForce());
    drawArrow(painter, at, pen_->f_guide_W.head<2>(), PaperColours::guideForce(), force_limit_N_);
  }
  const double lift_px = std::clamp(pen_->p_WT.z() * 1000.0, 0.0, 10.0) * 1.5;
  if (pen_->in_contact) {
    painter.setPen(QPen(Qt::white, 1.5));
    painter.setBrush(PaperColours::ink());
    painter.drawEllipse(at, kPenRadius_px, kPenRadius_px);
  } else {
    painter.setPen(QPen(PaperColours::ink(), 1.5));
    painter.setBrush(Qt::NoBrush);
    painter.drawEllipse(at, kPenRadius_px + lift_px, kPenRadius_px + lift_px);
  }
  painter.setBrush(Qt::NoBrush);
}

QString PaperView::readout() const {
  if (!pen_) return {};
  const double guide_N = pen_->f_guide_W.norm();
  const bool capped = guide_N > force_limit_N_;
  if (engineer_view_) {
    return tr("pen z %1 mm · fz %2 N · guidance %3 N%4")
        .arg(pen_->p_WT.z() * 1000.0, 0, 'f', 2)
        .arg(pen_->f_user_W.z(), 0, 'f', 2)
        .arg(guide_N, 0, 'f', 2)
        .arg(capped ? tr(" (capped at %1 N)").arg(force_limit_N_, 0, 'f', 2) : QString());
  }
  const double up_mm = std::max(0.0, pen_->p_WT.z() * 1000.0);
  return tr("%1 · pressing %2 N · help %3")
      .arg(pen_->in_contact ? tr("pen on the paper") : tr("pen %1 mm up").arg(up_mm, 0, 'f', 1))
      .arg(std::max(0.0, -pen_->f_user_W.z()), 0, 'f', 1)
      .arg(capped ? tr("%1 N (the pen's most)").arg(force_limit_N_, 0, 'f', 2) : tr("%1 N").arg(guide_N, 0, 'f', 1));
}

// Read-outs (millimetres and newtons for people), in a smaller font that the legend keeps.
void PaperView::drawReadouts(QPainter& painter, const QRectF& paper) const {
  painter.setPen(QColor(40, 40, 40));
  QFont small = font();
  small.setPointSizeF(small.pointSizeF() * 0.9);
  painter.setFont(small);
  const QRectF info(paper.left() + 8.0, paper.top() + 6.0, paper.width() - 16.0, 18.0);
  if (pen_) painter.drawText(info, Qt::AlignLeft | Qt::AlignVCenter, readout());
  if (hand_ != nullptr) {
    painter.drawText(info, Qt::AlignRight | Qt::AlignVCenter,
                     tr("press %1 N (wheel)").arg(hand_->input().press_N, 0, 'f', 1));
  }
}

// The legend along the paper's bottom edge, in as many rows as the paper's width needs, and a
// 10 mm scale bar at the right above it.
void PaperView::drawLegend(QPainter& painter, const QRectF& paper) const {
  struct LegendItem {
    QColor colour;
    QString text;
  };
  std::vector<LegendItem> items = {{PaperColours::reference(), tr("reference")},
                                   {PaperColours::ink(), tr("pen trail")},
                                   {PaperColours::overlay(), tr("reviewed trial")},
                                   {PaperColours::userForce(), tr("your force")},
                                   {PaperColours::guideForce(), tr("guidance")}};
  if (peer_trail_ != nullptr) items.push_back({PaperColours::peer(), tr("other station's pen")});
  // Each item's place: left to right, a new row (upward) where the next would pass the edge.
  constexpr double kRow = 18.0;
  std::vector<QPointF> at;
  double x = paper.left() + 10.0;
  int row = 0;
  for (const auto& item : items) {
    const double w = 30.0 + painter.fontMetrics().horizontalAdvance(item.text);
    if (x + w - 12.0 > paper.right() - 6.0 && x > paper.left() + 10.0) {
      x = paper.left() + 10.0;
      ++row;
    }
    at.emplace_back(x, static_cast<double>(row));
    x += w;
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    const double y = paper.bottom() - 12.0 - (row - at[i].y()) * kRow;
    painter.setPen(QPen(items[i].colour, 3.0));
    painter.drawLine(QPointF(at[i].x(), y - 4.0), QPointF(at[i].x() + 14.0, y - 4.0));
    painter.setPen(QColor(60, 60, 60));
    painter.drawText(QPointF(at[i].x() + 18.0, y), items[i].text);
  }
  // The scale bar, one row above the legend's top row.
  const double bar_px = 0.010 * mapping_.pixelsPerMetre();
  const QPointF bar_end(paper.right() - 12.0, paper.bottom() - 12.0 - (row + 1) * kRow - 2.0);
  painter.setPen(QPen(QColor(90, 90, 90), 2.0));
  painter.drawLine(bar_end - QPointF(bar_px, 0.0), bar_end);
  painter.drawText(QRectF(bar_end.x() - bar_px, bar_end.y() - 20.0, bar_px, 16.0), Qt::AlignCenter | Qt::TextDontClip,
                   tr("10 mm"));
}

// The banner (prompts, countdowns), when there is one.
void PaperView::drawBanner(QPainter& painter) const {
  if (banner_.isEmpty()) return;
  const BannerLayout banner = bannerLayout();
  painter.setFont(banner.font);
  painter.setPen(Qt::NoPen);
  painter.setBrush(QColor(30, 34, 44, 200));
  painter.drawRoundedRect(banner.box, 8.0, 8.0);
  painter.setPen(Qt::white);
  painter.drawText(banner.box.adjusted(kBannerMargin_px, 0.0, -kBannerMargin_px, 0.0),
                   Qt::AlignCenter | Qt::TextWordWrap, banner_);
}

void PaperView::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  painter.setRenderHint(QPainter::Antialiasing);
  painter.setRenderHint(QPainter::SmoothPixmapTransform);

  // The desk and the paper with its grain.
  const QRectF paper = mapping_.paperRectPx();
  drawPaper(painter, paper);

  // The letter guide under everything; the reference, a reviewed trial, the pen's trail: on the
  // paper shown only (a zoom shows part of it).
  painter.save();
  painter.setClipRect(paper);
  drawLetterGuide(painter);
  if (reference_shown_) drawTrail(painter, reference_, PaperColours::reference(), 3.0);
  drawTrail(painter, overlay_, PaperColours::overlay(), 2.5);
  if (peer_trail_ != nullptr) drawTrail(painter, *peer_trail_, PaperColours::peer(), 2.5);
  drawTrail(painter, trail_, PaperColours::ink(), 2.5);

  // Where the reference is now.
  if (cue_m_ && reference_shown_) {
    painter.setPen(QPen(PaperColours::reference(), 2.0));
    painter.drawEllipse(mapping_.toWidget(cue_m_->x(), cue_m_->y()), 8.0, 8.0);
  }

  // The hand's target (the cursor on the paper).
  if (hand_ != nullptr) {
    const QPointF target = mapping_.toWidget(hand_->input().x_m, hand_->input().y_m);
    painter.setPen(QPen(QColor(120, 120, 120), 1.0));
    painter.drawLine(target - QPointF(5, 0), target + QPointF(5, 0));
    painter.drawLine(target - QPointF(0, 5), target + QPointF(0, 5));
  }

  // The pen and its forces, then the other station's pen.
  drawPen(painter);
  drawPeerPen(painter);
  painter.restore();

  // Read-outs, legend, banner.
  drawReadouts(painter, paper);
  drawLegend(painter, paper);
  drawBanner(painter);
}

PaperView::BannerLayout PaperView::bannerLayout() const {
  const QRectF paper = mapping_.paperRectPx();
  const double width = paper.width() * 0.7;
  const double text_width = width - 2.0 * kBannerMargin_px;
  BannerLayout layout;
  layout.font = font();
  layout.font.setBold(true);
  // From 1.6 times the view's font down to its own size, the first that fits on two lines
  // (the size as resolved: a font set in pixels has no point size of its own).
  const double base_pt = QFontInfo(font()).pointSizeF();
  for (int step = 0; step <= 6; ++step) {
    layout.font.setPointSizeF(base_pt * (1.6 - 0.1 * step));
    const QFontMetricsF metrics(layout.font, this);
    const QRectF needed =
        metrics.boundingRect(QRectF(0.0, 0.0, text_width, 1e6), Qt::AlignCenter | Qt::TextWordWrap, banner_);
    layout.fits = needed.width() <= text_width + 0.5 && needed.height() <= 2.0 * metrics.lineSpacing() + 0.5;
    layout.box = QRectF(paper.left() + paper.width() * 0.15, paper.top() + 28.0, width,
                        std::max(40.0, std::min(needed.height(), 2.0 * metrics.lineSpacing()) + 12.0));
    if (layout.fits) break;
  }
  return layout;
}

}  // namespace hattr::studio
