#pragma once
/// The planar five-bar pantograph of the open pen (docs/hardware.md): two motors on a base line,
/// each turning a proximal link; two distal links meet at the pen. Kinematics in the device frame
/// D (x along the base line from motor 0 to motor 1, y towards the pen, origin midway between
/// the motors; joint angles from +x, counter-clockwise), and the map between D and hattr's W.

#include <Eigen/Core>

#include "hattr/core/types.hpp"

namespace hattr::device {

using Vec2 = Eigen::Vector2d;

struct FiveBarGeometry {
  double base_separation_m = 0.040;  ///< between the motor axes
  double proximal_m = 0.080;         ///< motor axis to elbow
  double distal_m = 0.100;           ///< elbow to pen
};

/// Forward kinematics: the pen in D for joint angles q (false where the distal links cannot
/// meet). The pen lies on the side of the elbows away from the base line.
bool fiveBarForward(const FiveBarGeometry& g, const Vec2& q, Vec2& pen_D) noexcept;

/// The Jacobian d(pen_D)/dq at q (where fiveBarForward succeeds); a singular pose (the distal
/// links in line) gives a matrix with a determinant near zero.
Eigen::Matrix2d fiveBarJacobian(const FiveBarGeometry& g, const Vec2& q) noexcept;

/// Inverse kinematics, elbows out (motor 0's elbow on the left of the line from its axis to the
/// pen, motor 1's on the right): false where the pen is out of reach.
bool fiveBarInverse(const FiveBarGeometry& g, const Vec2& pen_D, Vec2& q) noexcept;

/// Where the pantograph sits under the paper: the paper's origin in D, and D turned half a turn
/// about z from W (the base line lies beyond the paper, the links reach towards the writer: W's x
/// is D's -x, W's y is D's -y).
struct PlanarMount {
  Vec2 paper_origin_D = Vec2::Zero();  ///< where W's origin lies in D (a pen's home pose: referencePlanarPen)
};

inline Vec2 paperFromDevice(const PlanarMount& m, const Vec2& p_D) noexcept { return -(p_D - m.paper_origin_D); }
inline Vec2 deviceFromPaper(const PlanarMount& m, const Vec2& p_W) noexcept { return m.paper_origin_D - p_W; }

}  // namespace hattr::device
