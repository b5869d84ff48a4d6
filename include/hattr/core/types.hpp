#pragma once
/// Basic numeric types. Frame W (world): the paper plane is z = 0, x to the right,
/// y away from the writer, z up. See docs/units_and_frames.md.

#include <Eigen/Core>

namespace hattr {

/// A 3-vector of doubles in SI units; the frame is in the variable's name (p_WT, f_T_W).
using Vec3 = Eigen::Vector3d;

}  // namespace hattr
