#include "hattr/device/planar_pen.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/LU>

#include "hattr/core/error.hpp"
#include "hattr/openpen/protocol.h"

namespace hattr::device {
namespace {

// The reference build's writing area in W [m]: 80 mm × 50 mm around the home pose, where the
// linkage stays well away from its singular poses (docs/hardware.md).
constexpr double kAreaHalfWidth_m = 0.040;
constexpr double kAreaHalfDepth_m = 0.025;
// The slab about the table the planar pen reports its tip in (pen up: 1 mm over the paper).
constexpr double kSlab_m = 0.010;

Vec2 inPlane(const Vec3& v) noexcept { return v.head<2>(); }

/// The largest force the joints' torque limit puts on the pen in every direction at q [N].
double forceInEveryDirection(const PlanarPenSpec& spec, const Vec2& q, double torque_Nm) {
  const Eigen::Matrix2d J = fiveBarJacobian(spec.geometry, q);
  double weakest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 72; ++k) {
    const double angle = k * std::numbers::pi / 36.0;
    const Vec2 unit(std::cos(angle), std::sin(angle));
    const Vec2 per_newton = J.transpose() * unit;
    weakest = std::min(weakest, torque_Nm / std::max(per_newton.cwiseAbs().maxCoeff(), 1e-12));
  }
  return weakest;
}

}  // namespace

PlanarPenSpec referencePlanarPen() {
  PlanarPenSpec spec;
  fiveBarForward(spec.geometry, spec.home_q, spec.mount.paper_origin_D);  // W's origin: the home pose's pen
  return spec;
}

Vec2 jointAngles(const PlanarPenSpec& spec, std::int32_t count0, std::int32_t count1) noexcept {
  const double per_count = 2.0 * std::numbers::pi / spec.counts_per_joint_rev;
  return spec.home_q + per_count * Vec2(count0, count1);
}

bool penPosition(const PlanarPenSpec& spec, const Vec2& q, Vec3& p_WT) noexcept {
  Vec2 p_D;
  if (!fiveBarForward(spec.geometry, q, p_D)) return false;
  const Vec2 p_W = paperFromDevice(spec.mount, p_D);
  p_WT = Vec3(p_W.x(), p_W.y(), 0.0);
  return true;
}

Vec2 jointTorques(const PlanarPenSpec& spec, const Vec2& q, const Vec3& f_W) noexcept {
  // D is W turned half a turn about z: a force's in-plane part changes sign.
  const Vec2 f_D = -inPlane(f_W);
  return fiveBarJacobian(spec.geometry, q).transpose() * f_D;
}

std::array<std::int16_t, 2> motorEfforts(const PlanarPenSpec& spec, const Vec2& torque_Nm) noexcept {
  std::array<std::int16_t, 2> out{};
  for (int i = 0; i < 2; ++i) {
    const double sign = (spec.motor_sign >> i) & 1u ? -1.0 : 1.0;
    const double share = std::clamp(sign * torque_Nm[i] / spec.peak_torque_Nm, -1.0, 1.0);
    out[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(std::lround(share * HPEN_EFFORT_FULL));
  }
  return out;
}

Vec2 torquesForEfforts(const PlanarPenSpec& spec, double effort0, double effort1) noexcept {
  const Vec2 effort(effort0, effort1);
  Vec2 out;
  for (int i = 0; i < 2; ++i) {
    const double sign = (spec.motor_sign >> i) & 1u ? -1.0 : 1.0;
    out[i] = sign * effort[i] / HPEN_EFFORT_FULL * spec.peak_torque_Nm;
  }
  return out;
}

double sensorForce_N(const PlanarPenSpec& spec, double count) noexcept {
  return std::max(0.0, (count - spec.sensor_zero_count) * spec.sensor_N_per_count);
}

DeviceLimits planarPenLimits(const PlanarPenSpec& spec) {
  DeviceLimits limits;
  limits.degrees_of_freedom = 2;
  limits.workspace_min_m = Vec3(-kAreaHalfWidth_m, -kAreaHalfDepth_m, -kSlab_m);
  limits.workspace_max_m = Vec3(kAreaHalfWidth_m, kAreaHalfDepth_m, kSlab_m);
  // The weakest force in any direction anywhere in the area, on a 5 mm grid.
  double continuous = std::numeric_limits<double>::infinity();
  double peak = continuous;
  for (double x = -kAreaHalfWidth_m; x <= kAreaHalfWidth_m + 1e-9; x += 0.005) {
    for (double y = -kAreaHalfDepth_m; y <= kAreaHalfDepth_m + 1e-9; y += 0.005) {
      Vec2 q;
      HATTR_THROW_UNLESS(fiveBarInverse(spec.geometry, deviceFromPaper(spec.mount, Vec2(x, y)), q),
                         "the pen's links (base {} m, proximal {} m, distal {} m) cannot reach ({:.0f}, {:.0f}) mm of the "
                         "writing area, {:.0f} × {:.0f} mm around the home pose",
                         spec.geometry.base_separation_m, spec.geometry.proximal_m, spec.geometry.distal_m, x * 1e3,
                         y * 1e3, 2e3 * kAreaHalfWidth_m, 2e3 * kAreaHalfDepth_m);
      continuous = std::min(continuous, forceInEveryDirection(spec, q, spec.continuous_torque_Nm));
      peak = std::min(peak, forceInEveryDirection(spec, q, spec.peak_torque_Nm));
    }
  }
  limits.continuous_force_N = continuous;
  limits.peak_force_N = peak;
  limits.max_stiffness_N_per_m = 1000.0;
  limits.max_damping_N_s_per_m = 5.0;
  limits.nominal_rate_hz = spec.rate_hz;
  limits.mass_kg = 0.04;
  limits.damping_N_s_per_m = 1.0;
  return limits;
}

PlanarPlant::PlanarPlant(const PlanarPlantParams& params) : params_(params), q_(params.spec.home_q) {
  device::penPosition(params_.spec, q_, p_WT_);
}

void PlanarPlant::step(double dt_s, const Vec2& duty, const std::array<bool, 2>& driven, const HandCommand* hand) noexcept {
  const PlanarPlantParams& p = params_;
  const Eigen::Matrix2d J = fiveBarJacobian(p.spec.geometry, q_);
  // The pen in W (D turned half a turn: velocities change sign in the plane).
  const Vec2 v_D = J * qdot_;
  v_WT_ = Vec3(-v_D.x(), -v_D.y(), 0.0);

  // The hand: its in-plane pull, and its press onto the table (what the sensor reads).
  const Vec3 f_hand = hand != nullptr ? handForce(p.hand, *hand, p_WT_, v_WT_) : Vec3::Zero();
  normal_N_ = std::max(0.0, -f_hand.z());
  // The real paper's friction, Coulomb smoothed at low speed.
  const Vec2 v = inPlane(v_WT_);
  const double speed = v.norm();
  const Vec2 friction = speed > 0.0 ? Vec2(-p.table_friction * normal_N_ * std::tanh(speed / p.friction_speed_m_per_s) * v / speed)
                                    : Vec2::Zero();
  const Vec2 f_D = -(inPlane(f_hand) + friction);

  // The motors: a voltage (duty × supply) against the back-EMF through the winding.
  for (int i = 0; i < 2; ++i) {
    const double sign = (p.spec.motor_sign >> i) & 1u ? -1.0 : 1.0;
    const double motor_speed = sign * qdot_[i] * p.transmission;
    const double current = driven[static_cast<std::size_t>(i)] ? (duty[i] * p.supply_V - p.torque_constant_N_m_per_A * motor_speed) / p.winding_ohm : 0.0;
    motor_torque_[i] = sign * current * p.torque_constant_N_m_per_A * p.transmission;
  }

  // The linkage: joint inertia plus the pen's mass seen through the Jacobian.
  const Eigen::Matrix2d M = p.joint_inertia_kg_m2 * Eigen::Matrix2d::Identity() + p.pen_mass_kg * J.transpose() * J;
  Vec2 torque = motor_torque_ + J.transpose() * f_D - p.joint_damping_N_m_s * qdot_;
  for (int i = 0; i < 2; ++i) {
    const double beyond = std::abs(q_[i] - p.spec.home_q[i]) - p.joint_range_rad;
    if (beyond > 0.0) {
      const double outward = q_[i] > p.spec.home_q[i] ? 1.0 : -1.0;
      torque[i] -= outward * p.stop_stiffness_N_m_per_rad * beyond + p.stop_damping_N_m_s * qdot_[i];
    }
  }
  qdot_ += dt_s * M.inverse() * torque;
  q_ += dt_s * qdot_;
  device::penPosition(p.spec, q_, p_WT_);
}

}  // namespace hattr::device
