#include "ui/pen_scene_view.hpp"

#include <QEvent>
#include <QPainter>
#include <QPolygonF>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/relief_image.hpp"
#include "ui/paper_view.hpp"
#include "ui/trail_drawing.hpp"

namespace hattr::studio {
namespace {

constexpr double kYaw_rad = -20.0 * std::numbers::pi / 180.0;   // from the writer's left
constexpr double kPitch_rad = 40.0 * std::numbers::pi / 180.0;  // above the paper's plane
constexpr double kBarrelLength_m = 0.04;   // the part of the pen drawn above its tip
constexpr int kMeshCells = 48;             // cells along the paper's longer side
constexpr double kGridSpacing_m = 0.01;    // the paper's 10 mm grid
constexpr double kShownLift_m = 0.0003;    // a lift this high gets its line down to the paper
constexpr double kMargin_px = 12.0;

QPointF px(const Eigen::Vector2d& p) { return {p.x(), p.y()}; }

/// Paper-coloured, lit from the writer's left and above (Lambert, with ambient light).
QColor shaded(const Vec3& normal) {
  static const Vec3 light = Vec3(-0.4, -0.5, 1.0).normalized();
  const double lit = 0.6 + 0.4 * std::max(0.0, normal.normalized().dot(light));
  const QColor paper = paperColour();
  return QColor::fromRgbF(static_cast<float>(paper.redF() * lit), static_cast<float>(paper.greenF() * lit),
                          static_cast<float>(paper.blueF() * lit));
}

}  // namespace

PenSceneView::PenSceneView(PaperView* top, QWidget* parent) : QWidget(parent), top_(top) {
  setMinimumSize(160, 160);  // beside the top view, the window still fits a 1024 px screen
  top->installEventFilter(this);
  frameCamera();
}

void PenSceneView::setPaper(const render::HeightField& relief, double x_min_m, double y_min_m, double x_max_m,
                            double y_max_m) {
  relief_ = relief;
  x_min_m_ = x_min_m;
  y_min_m_ = y_min_m;
  x_max_m_ = x_max_m;
  y_max_m_ = y_max_m;
  // Raised so that the averaged relief (what is drawn) spans 3 % of the paper.
  exaggeration_ = 1.0;
  exaggeration_ = reliefExaggeration(drawnRelief(), std::max(x_max_m - x_min_m, y_max_m - y_min_m));
  drawn_relief_ = drawnRelief();
  frameCamera();
  update();
}

void PenSceneView::resizeEvent(QResizeEvent* event) {
  QWidget::resizeEvent(event);
  frameCamera();
}

bool PenSceneView::eventFilter(QObject* watched, QEvent* event) {
  if (watched == top_ && event->type() == QEvent::Paint && isVisible()) update();
  return false;
}

// The paper's rectangle, from its raised relief up to the barrel of a pen standing on it.
void PenSceneView::frameCamera() {
  const double extent = std::max(x_max_m_ - x_min_m_, y_max_m_ - y_min_m_);
  const double sunk = std::min(0.0, -0.03 * extent);
  camera_.frame(Vec3(x_min_m_, y_min_m_, sunk), Vec3(x_max_m_, y_max_m_, kBarrelLength_m), kYaw_rad, kPitch_rad,
                width(), height(), kMargin_px);
  surface_ = QImage();
}

double PenSceneView::surfaceHeight(double x_m, double y_m) const {
  return drawn_relief_.heightAt(x_m, y_m);  // 0 for flat paper
}

Vec3 PenSceneView::drawnPoint(const Vec3& p_W) const {
  return {p_W.x(), p_W.y(), surfaceHeight(p_W.x(), p_W.y()) + (p_W.z() - relief_.heightAt(p_W.x(), p_W.y()))};
}

std::pair<Vec3, Vec3> PenSceneView::barrelW(const Sample& pen) const {
  const Vec3 tip = drawnPoint(pen.p_WT);
  // A device without tilt reports altitude 0: drawn upright, and the read-out says so.
  const double altitude = pen.tilt_altitude_rad > 0.0 ? pen.tilt_altitude_rad : std::numbers::pi / 2.0;
  return {tip, penTop_W(tip, pen.tilt_azimuth_rad, altitude, kBarrelLength_m)};
}

std::pair<QPointF, QPointF> PenSceneView::barrelPx(const Sample& pen) const {
  const auto [tip, top] = barrelW(pen);
  return {px(camera_.toPixels(tip)), px(camera_.toPixels(top))};
}

// The raised relief the view draws: the relief averaged over each cell of a grid of
// kMeshCells along the paper's longer side (a grain finer than a cell would alias into noise),
// times the exaggeration. The mesh, the trails and the pen all stand on it.
render::HeightField PenSceneView::drawnRelief() const {
  if (relief_.flat()) return {};
  const double width_m = x_max_m_ - x_min_m_, height_m = y_max_m_ - y_min_m_;
  const double spacing = std::max(width_m, height_m) / kMeshCells;
  const int nx = std::max(2, static_cast<int>(std::ceil(width_m / spacing)) + 1);
  const int ny = std::max(2, static_cast<int>(std::ceil(height_m / spacing)) + 1);
  constexpr int kSub = 4;  // samples per cell side averaged
  return render::HeightField::fromFunction(nx, ny, Vec3(x_min_m_, y_min_m_, 0.0), spacing, [&](double x, double y) {
    double sum = 0.0;
    for (int j = 0; j < kSub; ++j) {
      for (int i = 0; i < kSub; ++i) {
        sum += relief_.heightAt(x + ((i + 0.5) / kSub - 0.5) * spacing, y + ((j + 0.5) / kSub - 0.5) * spacing);
      }
    }
    return exaggeration_ * sum / (kSub * kSub);
  });
}

// The raised relief's triangle mesh (render::HeightField::mesh), far triangles first, each
// shaded by its normal; the paper's 10 mm grid on it. At the screen's pixel ratio.
void PenSceneView::drawSurface() {
  const qreal ratio = devicePixelRatioF();
  surface_ = QImage(size() * ratio, QImage::Format_ARGB32_Premultiplied);
  surface_.setDevicePixelRatio(ratio);
  surface_.fill(Qt::transparent);
  QPainter painter(&surface_);
  const render::HeightField flat_paper = render::HeightField::fromFunction(
      2, 2, Vec3(x_min_m_, y_min_m_, 0.0), std::max(x_max_m_ - x_min_m_, y_max_m_ - y_min_m_),
      [](double, double) { return 0.0; });
  render::TriangleMesh mesh = (drawn_relief_.flat() ? flat_paper : drawn_relief_).mesh();
  for (Vec3& v : mesh.vertices) v.head<2>() = v.head<2>().cwiseMin(Eigen::Vector2d(x_max_m_, y_max_m_));  // the last cells end at the edge

  std::vector<std::pair<double, std::size_t>> order;
  order.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& [a, b, c] = mesh.triangles[t];
    order.emplace_back(camera_.depth(mesh.vertices[a] + mesh.vertices[b] + mesh.vertices[c]), t);
  }
  std::sort(order.begin(), order.end(), [](const auto& l, const auto& r) { return l.first > r.first; });
  for (const auto& [depth, t] : order) {
    const auto& [a, b, c] = mesh.triangles[t];
    const Vec3 &pa = mesh.vertices[a], &pb = mesh.vertices[b], &pc = mesh.vertices[c];
    Vec3 normal = (pb - pa).cross(pc - pa);
    if (normal.z() < 0.0) normal = -normal;
    const QColor colour = shaded(normal);
    painter.setPen(QPen(colour, 1.0));
    painter.setBrush(colour);
    const QPointF corners[3] = {px(camera_.toPixels(pa)), px(camera_.toPixels(pb)), px(camera_.toPixels(pc))};
    painter.drawPolygon(corners, 3);
  }

  // The 10 mm grid and the paper's edge, following the relief.
  painter.setRenderHint(QPainter::Antialiasing);
  const auto line = [&](double x0, double y0, double x1, double y1) {
    QPolygonF polyline;
    constexpr int kSteps = 32;
    for (int k = 0; k <= kSteps; ++k) {
      const double x = x0 + (x1 - x0) * k / kSteps, y = y0 + (y1 - y0) * k / kSteps;
      polyline << px(camera_.toPixels(Vec3(x, y, surfaceHeight(x, y))));
    }
    painter.drawPolyline(polyline);
  };
  painter.setPen(QPen(QColor(150, 160, 175, 110), 1.0));
  const auto first = [](double from) { return static_cast<int>(std::ceil(from / kGridSpacing_m - 1e-9)); };
  const auto last = [](double to) { return static_cast<int>(std::floor(to / kGridSpacing_m + 1e-9)); };
  for (int k = first(x_min_m_); k <= last(x_max_m_); ++k) line(k * kGridSpacing_m, y_min_m_, k * kGridSpacing_m, y_max_m_);
  for (int k = first(y_min_m_); k <= last(y_max_m_); ++k) line(x_min_m_, k * kGridSpacing_m, x_max_m_, k * kGridSpacing_m);
  painter.setPen(QPen(QColor(160, 160, 150), 1.5));
  line(x_min_m_, y_min_m_, x_max_m_, y_min_m_);
  line(x_max_m_, y_min_m_, x_max_m_, y_max_m_);
  line(x_max_m_, y_max_m_, x_min_m_, y_max_m_);
  line(x_min_m_, y_max_m_, x_min_m_, y_min_m_);
}

void PenSceneView::drawTrail(QPainter& painter, const Trail& trail, const QColor& colour, double width_px) const {
  drawTrailStrokes(painter, trail, colour, width_px, [this](const Eigen::Vector2d& p) {
    return px(camera_.toPixels(Vec3(p.x(), p.y(), surfaceHeight(p.x(), p.y()))));
  });
}

// The shadow of the barrel on the paper, the line down from a lifted tip, the barrel, its nib.
void PenSceneView::drawPen(QPainter& painter, const Sample& pen) const {
  const auto [tip, top] = barrelW(pen);
  const QPointF tip_px = px(camera_.toPixels(tip)), top_px = px(camera_.toPixels(top));
  const Vec3 tip_ground(tip.x(), tip.y(), surfaceHeight(tip.x(), tip.y()));
  const Vec3 top_ground(top.x(), top.y(), surfaceHeight(top.x(), top.y()));
  painter.setPen(QPen(QColor(40, 40, 50, 70), 5.0, Qt::SolidLine, Qt::RoundCap));
  painter.drawLine(px(camera_.toPixels(tip_ground)), px(camera_.toPixels(top_ground)));
  if (tip.z() - tip_ground.z() > kShownLift_m) {
    painter.setPen(QPen(QColor(90, 90, 100), 1.0, Qt::DashLine));
    painter.drawLine(tip_px, px(camera_.toPixels(tip_ground)));
  }
  painter.setPen(QPen(PaperColours::barrel(), 8.0, Qt::SolidLine, Qt::RoundCap));
  painter.drawLine(tip_px, top_px);
  painter.setPen(QPen(PaperColours::barrel().lighter(160), 2.0, Qt::SolidLine, Qt::RoundCap));
  painter.drawLine(tip_px + (top_px - tip_px) * 0.2, top_px);
  painter.setPen(QPen(PaperColours::ink(), 4.0, Qt::SolidLine, Qt::RoundCap));
  painter.drawLine(tip_px, tip_px + (top_px - tip_px) * 0.12);
  painter.setPen(QPen(Qt::white, 1.0));
  painter.setBrush(pen.in_contact ? QBrush(PaperColours::ink()) : QBrush(Qt::NoBrush));
  painter.drawEllipse(tip_px, 3.0, 3.0);
  painter.setBrush(Qt::NoBrush);
}

void PenSceneView::paintEvent(QPaintEvent*) {
  if (surface_.isNull() || surface_.size() != size()) drawSurface();
  QPainter painter(this);
  painter.fillRect(rect(), QColor(66, 70, 78));
  painter.drawImage(0, 0, surface_);
  painter.setRenderHint(QPainter::Antialiasing);
  if (top_->referenceShown()) drawTrail(painter, top_->reference(), PaperColours::reference(), 2.5);
  drawTrail(painter, top_->overlay(), PaperColours::overlay(), 2.0);
  drawTrail(painter, top_->trail(), PaperColours::ink(), 2.0);

  // The pen, and what it is doing in words (degrees and millimetres for people).
  painter.setPen(QColor(225, 225, 230));
  const QRectF info = rect().adjusted(8, 4, -8, -4);
  const QString relief = exaggeration_ > 1.0 ? tr(" · relief ×%1").arg(exaggeration_, 0, 'f', 0) : QString();
  if (const auto& pen = top_->pen()) {
    drawPen(painter, *pen);
    painter.setPen(QColor(225, 225, 230));
    const double lift_mm = (pen->p_WT.z() - relief_.heightAt(pen->p_WT.x(), pen->p_WT.y())) * 1e3;
    const QString tilt = pen->tilt_altitude_rad > 0.0
                             ? tr("altitude %1° · azimuth %2°")
                                   .arg(pen->tilt_altitude_rad * 180.0 / std::numbers::pi, 0, 'f', 0)
                                   .arg(pen->tilt_azimuth_rad * 180.0 / std::numbers::pi, 0, 'f', 0)
                             : tr("tilt not measured (drawn upright)");
    painter.drawText(info, Qt::AlignLeft | Qt::AlignTop | Qt::TextWordWrap,
                     tr("%1 · %2 mm above the paper%3").arg(tilt).arg(std::max(0.0, lift_mm), 0, 'f', 1).arg(relief));
  } else {
    painter.drawText(info, Qt::AlignLeft | Qt::AlignTop, tr("3-D view: no pen%1").arg(relief));
  }
}

}  // namespace hattr::studio
