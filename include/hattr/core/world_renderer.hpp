#pragma once
/// The servo loop's interface to the world the pen touches (the paper), and the forces it
/// gives back. SI units, frame W (docs/units_and_frames.md).

#include "hattr/core/pen_state.hpp"
#include "hattr/core/types.hpp"

namespace hattr {

/// The world's (the paper's) response to the pen at one tick.
struct ContactForces {
  Vec3 f_on_pen_W = Vec3::Zero();     ///< force the paper exerts on the pen [N]
  Vec3 f_on_paper_W = Vec3::Zero();   ///< force the pen exerts on the paper: the user's force [N]
  bool in_contact = false;            ///< the tip touches the paper
};

/// Renders the world the pen touches. Runs on the servo thread: noexcept, no allocation,
/// no locks, no I/O. Implemented by the render module.
class WorldRenderer {
 public:
  virtual ~WorldRenderer() = default;
  /// Computes the contact forces for the pen at this tick; dt_s is the measured period.
  virtual void render(const PenState& pen, double dt_s, ContactForces& out) noexcept = 0;
  /// Forgets contact history (proxy, filters) before a new trial. Not on the servo thread.
  virtual void reset() noexcept {}
};

}  // namespace hattr
