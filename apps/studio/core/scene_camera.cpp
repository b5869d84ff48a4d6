#include "core/scene_camera.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hattr::studio {

// The camera's axes: at yaw 0 it looks along +y, tilted down by the pitch; the yaw turns
// the whole frame about W's z.
void SceneCamera::frame(const Vec3& box_min_W, const Vec3& box_max_W, double yaw_rad, double pitch_rad, int width_px,
                        int height_px, double margin_px) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const auto turned = [&](const Vec3& v) { return Vec3(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()); };
  forward_ = turned(Vec3(0.0, std::cos(pitch_rad), -std::sin(pitch_rad)));
  right_ = turned(Vec3::UnitX());
  up_ = right_.cross(forward_);

  // The box's corners on the view plane, fitted into the viewport.
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p((corner & 1) ? box_max_W.x() : box_min_W.x(), (corner & 2) ? box_max_W.y() : box_min_W.y(),
                 (corner & 4) ? box_max_W.z() : box_min_W.z());
    const Eigen::Vector2d uv(p.dot(right_), p.dot(up_));
    lo = lo.cwiseMin(uv);
    hi = hi.cwiseMax(uv);
  }
  const double room_x = std::max(1.0, width_px - 2.0 * margin_px), room_y = std::max(1.0, height_px - 2.0 * margin_px);
  const Eigen::Vector2d span = (hi - lo).cwiseMax(1e-9);
  scale_ = std::min(room_x / span.x(), room_y / span.y());
  centre_uv_ = 0.5 * (lo + hi);
  centre_px_ = Eigen::Vector2d(0.5 * width_px, 0.5 * height_px);
}

Eigen::Vector2d SceneCamera::toPixels(const Vec3& p_W) const noexcept {
  const Eigen::Vector2d uv(p_W.dot(right_), p_W.dot(up_));
  const Eigen::Vector2d d = (uv - centre_uv_) * scale_;
  return {centre_px_.x() + d.x(), centre_px_.y() - d.y()};
}

Vec3 penTop_W(const Vec3& tip_W, double azimuth_rad, double altitude_rad, double length_m) noexcept {
  const double along_paper = length_m * std::cos(altitude_rad);
  return tip_W + Vec3(along_paper * std::sin(azimuth_rad), along_paper * std::cos(azimuth_rad),
                      length_m * std::sin(altitude_rad));
}

double reliefExaggeration(const render::HeightField& relief, double paper_extent_m, double share) {
  if (relief.flat()) return 1.0;
  // The heights at the grid's vertices.
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (int j = 0; j < relief.ny(); ++j) {
    for (int i = 0; i < relief.nx(); ++i) {
      const double h = relief.heightAt(relief.origin_W().x() + i * relief.spacing_m(), relief.origin_W().y() + j * relief.spacing_m());
      lowest = std::min(lowest, h);
      highest = std::max(highest, h);
    }
  }
  const double range_m = highest - lowest;
  if (!(range_m > 0.0)) return 1.0;
  return std::max(1.0, share * paper_extent_m / range_m);
}

}  // namespace hattr::studio
