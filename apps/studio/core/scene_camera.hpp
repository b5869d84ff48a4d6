#pragma once
/// The geometry of the studio's 3-D view (ui/pen_scene_view.hpp): an orthographic camera that
/// looks at the paper from the writer's side and above, fitted to a viewport; where the far end
/// of the pen's barrel is for its tilt; and how much the paper's relief is raised so that a
/// grain of micrometres can be seen beside a pen of centimetres. SI units and W; pixels only
/// as the camera's output. No Qt: unit-tested without widgets.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "hattr/core/types.hpp"
#include "hattr/render/height_field.hpp"

namespace hattr::studio {

class SceneCamera {
 public:
  /// Looks at the box [box_min, box_max] (W, metres) from `yaw_rad` around W's z (0: from
  /// the writer's side, W's -y, looking toward +y; positive: from further right) and
  /// `pitch_rad` above the paper's plane (π/2: from straight above), fitted into a
  /// `width_px` × `height_px` viewport with `margin_px` on every side.
  void frame(const Vec3& box_min_W, const Vec3& box_max_W, double yaw_rad, double pitch_rad, int width_px,
             int height_px, double margin_px);
  /// The pixel (x right, y down) a point of W falls on.
  [[nodiscard]] Eigen::Vector2d toPixels(const Vec3& p_W) const noexcept;
  /// How far along the view direction a point lies (larger: farther from the viewer) [m].
  [[nodiscard]] double depth(const Vec3& p_W) const noexcept { return p_W.dot(forward_); }
  /// The direction the camera looks along (unit, W).
  [[nodiscard]] const Vec3& forward() const noexcept { return forward_; }
  /// Pixels per metre on the screen.
  [[nodiscard]] double pixelsPerMetre() const noexcept { return scale_; }

 private:
  Vec3 right_ = Vec3::UnitX();
  Vec3 up_ = Vec3::UnitZ();
  Vec3 forward_ = Vec3::UnitY();
  Eigen::Vector2d centre_uv_ = Eigen::Vector2d::Zero();  // the box's centre on the view plane [m]
  Eigen::Vector2d centre_px_ = Eigen::Vector2d::Zero();  // the viewport's centre [px]
  double scale_ = 1.0;                                   // [px/m]
};

/// The far end of a pen's barrel `length_m` from its tip, at `altitude_rad` above the paper
/// and `azimuth_rad` (docs/units_and_frames.md: clockwise seen from above, from W's +y to the
/// barrel's projection on the paper).
[[nodiscard]] Vec3 penTop_W(const Vec3& tip_W, double azimuth_rad, double altitude_rad, double length_m) noexcept;

/// The factor the view raises the relief by: its height range becomes `share` of the paper's
/// larger side, never lowered (1 for flat paper or a relief already that high).
[[nodiscard]] double reliefExaggeration(const render::HeightField& relief, double paper_extent_m, double share = 0.03);

}  // namespace hattr::studio
