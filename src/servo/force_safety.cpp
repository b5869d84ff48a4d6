#include "hattr/servo/force_safety.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hattr/core/error.hpp"

namespace hattr::servo {
namespace {

/// No stage or wall ever asks for this much force on a hand-held pen: above it the request is
/// a broken computation, not a force, and the path latches a fault instead of clamping (the
/// clamp's arithmetic would overflow far above it, near 1e154 N).
constexpr double kAbsurdForce_N = 1e6;

bool sane(const Vec3& force) noexcept { return force.allFinite() && force.cwiseAbs().maxCoeff() <= kAbsurdForce_N; }

}  // namespace

ForceSafety::ForceSafety(const SafetyConfig& config, const device::DeviceLimits& limits)
    : config_(config),
      wall_min_m_(limits.workspace_min_m.array() + config.wall_margin_m),
      wall_max_m_(limits.workspace_max_m.array() - config.wall_margin_m),
      max_force_N_(config.max_force_N > 0.0 ? std::min(config.max_force_N, limits.peak_force_N)
                                            : limits.continuous_force_N) {
  const auto check = [](double value, const char* name) {
    HATTR_THROW_UNLESS(std::isfinite(value) && value >= 0.0, "safety: {}: expected a finite number >= 0, got {}",
                       name, value);
  };
  check(config.max_force_N, "max_force_N");
  check(config.max_rate_N_per_s, "max_rate_N_per_s");
  check(config.ramp_time_s, "ramp_time_s");
  check(config.wall_margin_m, "wall_margin_m");
  check(config.wall_stiffness_N_per_m, "wall_stiffness_N_per_m");
  HATTR_THROW_UNLESS(config.max_rate_N_per_s > 0.0, "safety: max_rate_N_per_s: expected > 0, got {}",
                     config.max_rate_N_per_s);
  // The clamp divides by the limit: a device that declares no force is refused here.
  HATTR_THROW_UNLESS(std::isfinite(max_force_N_) && max_force_N_ > 0.0,
                     "safety: the device's force limit must be a finite number > 0 N, got {} (continuous {} N, peak {} N)",
                     max_force_N_, limits.continuous_force_N, limits.peak_force_N);
}

Vec3 ForceSafety::softWallForce(const Vec3& p_WT) const noexcept {
  const Vec3 below = (wall_min_m_ - p_WT).cwiseMax(0.0);
  const Vec3 above = (p_WT - wall_max_m_).cwiseMax(0.0);
  return config_.wall_stiffness_N_per_m * (below - above);
}

Vec3 ForceSafety::filter(const Vec3& world_W, const Vec3& guidance_W, const Vec3& p_WT, double dt_s) noexcept {
  // A latched fault, or a bad number now (non-finite, or absurdly large): zero force at once
  // (no rate limit on stopping). Walls far outside the workspace count as absurd too.
  const Vec3 world = sane(world_W) && p_WT.allFinite() ? Vec3(world_W + softWallForce(p_WT)) : Vec3(Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  if (fault_ == SafetyFault::kNone && !(sane(world) && sane(guidance_W) && std::isfinite(dt_s))) {
    latchFault(SafetyFault::kNonFiniteForce);
  }
  if (fault_ != SafetyFault::kNone) {
    last_W_.setZero();
    return last_W_;
  }
  const double dt = std::max(dt_s, 0.0);

  // Soft walls with the world's force, then the magnitude clamp: the guidance is scaled down
  // first (the largest s in [0, 1] with |W + s·G| <= max), the world's force only if it alone
  // exceeds the limit.
  Vec3 force = world + guidance_W;
  if (force.norm() > max_force_N_) {
    ++clamps_;
    const double w2 = world.squaredNorm(), m2 = max_force_N_ * max_force_N_;
    if (w2 >= m2) {
      force = world * (max_force_N_ / std::sqrt(w2));
    } else {
      const double a = guidance_W.squaredNorm(), b = 2.0 * world.dot(guidance_W), c = w2 - m2;
      // c < 0: one positive root; a guidance too small to square (denormal) gives way entirely.
      const double s = a > 0.0 ? (-b + std::sqrt(std::max(0.0, b * b - 4.0 * a * c))) / (2.0 * a) : 0.0;
      force = world + std::clamp(std::isfinite(s) ? s : 0.0, 0.0, 1.0) * guidance_W;
    }
  }

  // Ramp in.
  ramp_ = config_.ramp_time_s > 0.0 ? std::min(1.0, ramp_ + dt / config_.ramp_time_s) : 1.0;
  force *= ramp_;

  // Rate limit: move from the last output toward the target by at most max_rate·dt. Both
  // lie inside the clamp ball, so the result does too.
  const Vec3 step = force - last_W_;
  const double max_step = config_.max_rate_N_per_s * dt;
  const double step_norm = step.norm();
  last_W_ += step_norm > max_step ? Vec3(step * (max_step / step_norm)) : step;
  // Total by construction; checked anyway, since a device must never see anything else.
  if (!last_W_.allFinite() || last_W_.norm() > max_force_N_ * (1.0 + 1e-9)) latchFault(SafetyFault::kNonFiniteForce);
  return last_W_;
}

void ForceSafety::latchFault(SafetyFault fault) noexcept {
  if (fault_ == SafetyFault::kNone) ++faults_;
  fault_ = fault;
  ramp_ = 0.0;
  last_W_.setZero();
}

void ForceSafety::clearFault() noexcept {
  fault_ = SafetyFault::kNone;
  restartRamp();
}

void ForceSafety::restartRamp() noexcept {
  ramp_ = 0.0;
  last_W_.setZero();
}

}  // namespace hattr::servo
