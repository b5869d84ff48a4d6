#pragma once
/// The open pen (docs/hardware.md) as hattr computes with it: the constants its firmware declares
/// (PlanarPenSpec, from the IDENTITY packet), the maps from encoder counts to the pen and from a
/// force on the pen to motor efforts (Jacobian transpose), the limits that follow, and the plant
/// that the simulated planar pen (sim://planar) and the firmware emulator (hattr-pen-emulator)
/// both integrate: two motors with back-EMF turning a five-bar, the hand that holds the pen, and
/// the real table under it.
///
/// A planar pen moves only in the paper's plane: the table holds the pen up (the paper's normal
/// spring is the real table), the pen's force sensor measures how hard the writer presses, and
/// guidance acts in the plane (docs/hardware.md, "What a planar pen renders").

#include <array>
#include <cstdint>
#include <string>

#include "hattr/core/device_limits.hpp"
#include "hattr/core/hand_command.hpp"
#include "hattr/device/five_bar.hpp"
#include "hattr/device/hand.hpp"

namespace hattr::device {

/// What the pen's firmware declares about itself, in SI (referencePlanarPen(): the reference build).
struct PlanarPenSpec {
  std::string model = "openpen-5bar";
  unsigned firmware_build = 0;
  FiveBarGeometry geometry;
  Vec2 home_q = Vec2(2.35619449, 0.78539816);  ///< joint angles at the home pose [rad]
  double counts_per_joint_rev = 20000.0;
  double peak_torque_Nm = 0.693;                ///< joint torque at full effort
  double continuous_torque_Nm = 0.277;
  double sensor_N_per_count = 0.010851;
  double sensor_zero_count = 102.0;
  double sensor_max_count = 1023.0;
  unsigned motor_sign = 0;                      ///< bit i: motor i's positive effort turns clockwise
  double rate_hz = 1000.0;
  double watchdog_s = 0.020;
  PlanarMount mount;                            ///< W's origin: where the pen is at the home pose
};

/// The reference build's constants (firmware/openpen/config.h), W's origin at its home pose.
PlanarPenSpec referencePlanarPen();

/// How both planar devices (serial://, sim://planar) report the pen's height: on the paper while
/// the writer presses at least `contact_N`, else lifted kPlanarLiftedHeight_m over it.
inline constexpr double kPlanarContact_N = 0.05;
inline constexpr double kPlanarLiftedHeight_m = 0.001;
inline double planarTipHeight(double press_N, double contact_N) noexcept {
  return press_N >= contact_N ? 0.0 : kPlanarLiftedHeight_m;
}



/// The joint angles for encoder counts since the home pose.
Vec2 jointAngles(const PlanarPenSpec& spec, std::int32_t count0, std::int32_t count1) noexcept;
/// The pen in W (z = 0) at joint angles q; false where the linkage cannot be.
bool penPosition(const PlanarPenSpec& spec, const Vec2& q, Vec3& p_WT) noexcept;
/// The joint torques that put the in-plane part of `f_W` on the pen (τ = Jᵀ·f in D) [N·m].
Vec2 jointTorques(const PlanarPenSpec& spec, const Vec2& q, const Vec3& f_W) noexcept;
/// The motor efforts (±HPEN_EFFORT_FULL at the peak torque, the wiring's signs) for joint torques.
std::array<std::int16_t, 2> motorEfforts(const PlanarPenSpec& spec, const Vec2& torque_Nm) noexcept;
/// The joint torque each motor applies for an effort (the inverse of motorEfforts).
Vec2 torquesForEfforts(const PlanarPenSpec& spec, double effort0, double effort1) noexcept;
/// The pen force sensor's reading in newtons (never negative).
double sensorForce_N(const PlanarPenSpec& spec, double count) noexcept;

/// The planar pen's limits: its writing area in W (a box, z a thin slab about the table), the
/// force it sustains and peaks at in every direction everywhere in that area, the stiffness and
/// damping it renders stably. Computed over a grid of the area. Throws InputError when the links
/// cannot reach all of it.
DeviceLimits planarPenLimits(const PlanarPenSpec& spec);

/// The physical pen the firmware drives (or that sim://planar is): motors, linkage, hand, table.
struct PlanarPlantParams {
  PlanarPenSpec spec = referencePlanarPen();
  double joint_inertia_kg_m2 = 2.5e-4;     ///< rotor through the capstan plus the proximal link
  double pen_mass_kg = 0.010;              ///< the pen holder and the distal links' share, at the tip
  double joint_damping_N_m_s = 2e-4;       ///< bearings and capstan, per joint
  double supply_V = 12.0;
  double winding_ohm = 4.0;
  double torque_constant_N_m_per_A = 0.0231;  ///< at the motor (also the back-EMF constant, V·s)
  double transmission = 10.0;              ///< the capstan's ratio
  double table_friction = 0.15;            ///< the real paper on the real table: μ of the pen's tip
  double friction_speed_m_per_s = 0.001;   ///< Coulomb friction smoothed below this speed
  /// The linkage's mechanical stops: each joint turns at most this far either way from home, where
  /// a stiff, damped stop holds it.
  double joint_range_rad = 1.0;
  double stop_stiffness_N_m_per_rad = 20.0;
  double stop_damping_N_m_s = 0.02;
  HandImpedance hand;
};

/// The plant: joint state, integrated by semi-implicit Euler (the linkage's velocity-product
/// terms are left out: at writing speeds they are under 1 % of the inertial forces).
class PlanarPlant {
 public:
  explicit PlanarPlant(const PlanarPlantParams& params);

  /// Advances dt under the motors' duty cycles (−1..1 of the supply; `driven[i]` false: motor i's
  /// winding is open and it coasts) and the hand's command (null: nobody holds the pen).
  void step(double dt_s, const Vec2& duty, const std::array<bool, 2>& driven, const HandCommand* hand) noexcept;

  [[nodiscard]] const Vec2& q() const noexcept { return q_; }
  [[nodiscard]] const Vec2& qdot() const noexcept { return qdot_; }
  [[nodiscard]] const Vec3& penPosition() const noexcept { return p_WT_; }
  [[nodiscard]] const Vec3& penVelocity() const noexcept { return v_WT_; }
  /// How hard the hand presses the pen onto the table [N] (what the force sensor reads).
  [[nodiscard]] double normalForce_N() const noexcept { return normal_N_; }
  /// The joint torques the motors gave at the last step [N·m].
  [[nodiscard]] const Vec2& motorTorque() const noexcept { return motor_torque_; }
  [[nodiscard]] const PlanarPlantParams& params() const noexcept { return params_; }

 private:
  PlanarPlantParams params_;
  Vec2 q_;
  Vec2 qdot_ = Vec2::Zero();
  Vec3 p_WT_ = Vec3::Zero();
  Vec3 v_WT_ = Vec3::Zero();
  Vec2 motor_torque_ = Vec2::Zero();
  double normal_N_ = 0.0;
};

}  // namespace hattr::device
