#include "hattr/device/five_bar.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

namespace hattr::device {
namespace {

Vec2 motorAxis(const FiveBarGeometry& g, int i) noexcept {
  return Vec2(i == 0 ? -0.5 * g.base_separation_m : 0.5 * g.base_separation_m, 0.0);
}

Vec2 elbow(const FiveBarGeometry& g, int i, double q) noexcept {
  return motorAxis(g, i) + g.proximal_m * Vec2(std::cos(q), std::sin(q));
}

}  // namespace

bool fiveBarForward(const FiveBarGeometry& g, const Vec2& q, Vec2& pen_D) noexcept {
  // The pen is where two circles of the distal length around the elbows meet.
  const Vec2 e0 = elbow(g, 0, q.x());
  const Vec2 e1 = elbow(g, 1, q.y());
  const Vec2 between = e1 - e0;
  const double span = between.norm();
  const double half = 0.5 * span;
  if (span < 1e-9 || half > g.distal_m) return false;
  const double height = std::sqrt(g.distal_m * g.distal_m - half * half);
  const Vec2 across(-between.y() / span, between.x() / span);
  pen_D = e0 + 0.5 * between + height * across;
  return true;
}

Eigen::Matrix2d fiveBarJacobian(const FiveBarGeometry& g, const Vec2& q) noexcept {
  // Each distal link keeps its length: (p − e_i)·(ṗ − ė_i) = 0, with ė_i = q̇_i·t_i.
  Vec2 pen;
  if (!fiveBarForward(g, q, pen)) return Eigen::Matrix2d::Zero();
  Eigen::Matrix2d rows;
  Eigen::Matrix2d tangents = Eigen::Matrix2d::Zero();
  for (int i = 0; i < 2; ++i) {
    const double qi = q[i];
    const Vec2 link = pen - elbow(g, i, qi);
    rows.row(i) = link.transpose();
    tangents(i, i) = link.dot(g.proximal_m * Vec2(-std::sin(qi), std::cos(qi)));
  }
  if (std::abs(rows.determinant()) < 1e-15) return Eigen::Matrix2d::Zero();
  return rows.inverse() * tangents;
}

bool fiveBarInverse(const FiveBarGeometry& g, const Vec2& pen_D, Vec2& q) noexcept {
  // Each elbow is where the proximal circle around its motor meets the distal circle around the pen.
  for (int i = 0; i < 2; ++i) {
    const Vec2 axis = motorAxis(g, i);
    const Vec2 to_pen = pen_D - axis;
    const double d = to_pen.norm();
    if (d < 1e-9 || d > g.proximal_m + g.distal_m || d < std::abs(g.proximal_m - g.distal_m)) return false;
    const double along = (g.proximal_m * g.proximal_m - g.distal_m * g.distal_m + d * d) / (2.0 * d);
    const double off = std::sqrt(std::max(g.proximal_m * g.proximal_m - along * along, 0.0));
    const Vec2 unit = to_pen / d;
    const Vec2 left(-unit.y(), unit.x());
    const Vec2 e = axis + along * unit + (i == 0 ? off : -off) * left;
    q[i] = std::atan2(e.y() - axis.y(), e.x() - axis.x());
  }
  return true;
}

}  // namespace hattr::device
