#pragma once
/// What a simulated hand wants at one instant: the command a HandScript gives the simulated
/// pen (hattr::device), and what a udp:// client sends a served simulated pen. SI, frame W.

#include "hattr/core/types.hpp"

namespace hattr {

/// What the hand wants at one instant.
struct HandCommand {
  Vec3 p_target_W = Vec3::Zero();   ///< where the hand pulls the tip [m]
  Vec3 v_target_W = Vec3::Zero();   ///< the target's velocity [m/s]
  double press_N = 0.0;             ///< intended axial force toward the tip [N] (>= 0)
  double azimuth_rad = 0.0;         ///< pen azimuth (see docs/units_and_frames.md)
  double altitude_rad = 1.0471975511965976;  ///< pen altitude above the paper (60°)
  bool pen_down = false;            ///< the hand means to write
  /// The share of the hand's impedance it writes with in the paper plane (1: the full
  /// HandImpedance; a hand that writes from a feedforward force holds the pen more loosely).
  double grip = 1.0;
  /// A feedforward force the hand adds in the paper plane [N, W] (z ignored).
  Vec3 push_W = Vec3::Zero();
  /// The height of the writing surface under the target [m, W]: the fingers' reach under it is
  /// measured from here (the hand rests on the paper, whatever its relief). A trial fills it from
  /// its paper's relief (session::SettlingHand); 0 is the writing plane.
  double surface_z_m = 0.0;
};

}  // namespace hattr
