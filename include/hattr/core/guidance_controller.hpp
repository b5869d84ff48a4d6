#pragma once
/// The servo loop's interface to an assistance force (the training strategies). SI units,
/// frame W (docs/units_and_frames.md).

#include "hattr/core/pen_state.hpp"
#include "hattr/core/types.hpp"
#include "hattr/core/world_renderer.hpp"

namespace hattr {

/// Computes an assistance force. Same rules as WorldRenderer. Implemented by the guidance
/// module (the training modes).
class GuidanceController {
 public:
  virtual ~GuidanceController() = default;
  /// Guidance force on the pen [N] for this tick (pen.t_s is the loop time).
  virtual Vec3 compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept = 0;
  /// Handles a parameter command from the mailbox (see servo::ServoCommand); returns false
  /// if it does not know the parameter.
  virtual bool setParameter(int /*parameter*/, double /*value*/) noexcept { return false; }
  virtual void reset() noexcept {}
};

}  // namespace hattr
