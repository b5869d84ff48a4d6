#pragma once
/// What the servo loop reads from a device once per tick, and what the world and the
/// guidance compute from it. SI units, frame W (docs/units_and_frames.md).

#include <cstdint>

#include "hattr/core/types.hpp"

namespace hattr {

/// The pen as a device reports it at one tick.
struct PenState {
  double t_s = 0.0;                   ///< loop time of this reading [s]
  Vec3 p_WT = Vec3::Zero();           ///< pen-tip position in W [m]
  Vec3 v_WT = Vec3::Zero();           ///< pen-tip velocity in W [m/s]
  std::uint32_t buttons = 0;          ///< bit 0: the stylus button / pen switch
  bool has_force = false;             ///< f_measured_W is a force-sensor reading
  Vec3 f_measured_W = Vec3::Zero();   ///< force the user applies through the pen [N]
  bool has_pressure = false;          ///< pressure_raw is meaningful
  double pressure_raw = 0.0;          ///< raw axial pressure, device units
  bool has_tilt = false;              ///< azimuth and altitude are meaningful
  double azimuth_rad = 0.0;           ///< clockwise from +y to the barrel's projection [rad]
  double altitude_rad = 0.0;          ///< pen axis above the paper [rad]
};

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
