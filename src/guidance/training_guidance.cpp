#include "hattr/guidance/training_guidance.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/passivity.hpp"

namespace hattr::guidance {

std::string_view modeName(TrainingMode mode) {
  switch (mode) {
    case TrainingMode::kBasic: return "BASIC";
    case TrainingMode::kPositionControl: return "PCONTROL";
    case TrainingMode::kForceControl: return "ALPHA";
    case TrainingMode::kMentorObserve: return "MENTOR-OBSERVE";
    case TrainingMode::kMentorPosition: return "MENTOR-POSITION";
    case TrainingMode::kMentorForce: return "MENTOR-FORCE";
    case TrainingMode::kMentorBilateral: return "MENTOR-BILATERAL";
  }
  return "?";
}

TrainingMode parseMode(std::string_view text) {
  std::string upper(text);
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return std::toupper(c); });
  for (int m = 0; m <= static_cast<int>(TrainingMode::kMentorBilateral); ++m) {
    if (upper == modeName(static_cast<TrainingMode>(m))) return static_cast<TrainingMode>(m);
  }
  throw InputError(fmt::format("mode: expected basic, pcontrol, alpha, mentor-observe, mentor-position, mentor-force "
                               "or mentor-bilateral, got \"{}\"", text));
}

std::vector<std::string> clampGains(GuidanceConfig& config, const DeviceLimits& limits, double rate_hz,
                                    const WorldImpedance& world) {
  // PCONTROL acts in the paper plane, beside the friction proxy's spring.
  std::vector<std::string> changes =
      clampImpedance(config.position.kp_N_per_m, config.position.kd_N_s_per_m,
                     {.stiffness_name = "PCONTROL Kp", .damping_name = "PCONTROL Kd",
                      .k_other_N_per_m = world.tangential_stiffness_N_per_m},
                     limits, rate_hz);

  // ALPHA acts through the paper: on the normal axis its force Kp·e + Kd·ė changes with the
  // pen's depth like a stiffness Kp·K and a damping Kp·C + Kd·K, beside the paper's own;
  // in the plane like Kp·Kt and Kd·Kt beside the friction spring.
  ForceGains& f = config.force;
  const ForceGains before = f;
  const double kn = world.normal_stiffness_N_per_m, cn = world.normal_damping_N_s_per_m;
  double k_eff = f.kp * kn, c_eff = f.kp * cn + f.kd_s * kn;
  const auto normal = clampImpedance(k_eff, c_eff,
                                     {.stiffness_name = "ALPHA effective stiffness Kp·K (normal)",
                                      .damping_name = "ALPHA effective damping Kp·C + Kd·K (normal)",
                                      .k_other_N_per_m = kn, .c_other_N_s_per_m = cn},
                                     limits, rate_hz);
  f.kp = k_eff / kn;
  f.kd_s = std::max(0.0, (c_eff - f.kp * cn) / kn);
  const double kt = world.tangential_stiffness_N_per_m;
  k_eff = f.kp * kt;
  c_eff = f.kd_s * kt;
  const auto tangential = clampImpedance(k_eff, c_eff,
                                         {.stiffness_name = "ALPHA effective stiffness Kp·Kt (plane)",
                                          .damping_name = "ALPHA effective damping Kd·Kt (plane)",
                                          .k_other_N_per_m = kt},
                                         limits, rate_hz);
  f.kp = k_eff / kt;
  f.kd_s = c_eff / kt;
  changes.insert(changes.end(), normal.begin(), normal.end());
  changes.insert(changes.end(), tangential.begin(), tangential.end());
  if (f.kp != before.kp) changes.push_back(fmt::format("ALPHA Kp {:.4g} -> {:.4g}", before.kp, f.kp));
  if (f.kd_s != before.kd_s) changes.push_back(fmt::format("ALPHA Kd {:.4g} s -> {:.4g} s", before.kd_s, f.kd_s));
  return changes;
}

TrainingGuidance::TrainingGuidance(std::shared_ptr<const ReferenceTrajectory> reference, const GuidanceConfig& config)
    : reference_(std::move(reference)), config_(config), mode_(config.mode), previous_mode_(config.mode) {
  HATTR_THROW_UNLESS(reference_ || config.mode == TrainingMode::kBasic || isMentored(config.mode),
                     "guidance: mode {} needs an expert reference", modeName(config.mode));
  const auto check = [](double value, const char* name) {
    HATTR_THROW_UNLESS(std::isfinite(value) && value >= 0.0, "guidance: {}: expected a finite number >= 0, got {}",
                       name, value);
  };
  check(config.position.kp_N_per_m, "PCONTROL Kp");
  check(config.position.kd_N_s_per_m, "PCONTROL Kd");
  check(config.force.kp, "ALPHA Kp");
  check(config.force.kd_s, "ALPHA Kd");
  check(config.crossfade_s, "cross-fade time");
  check(config.lift_fade_s, "lift fade time");
  HATTR_THROW_UNLESS(config.force.derivative_cutoff_hz > 0.0, "guidance: ALPHA derivative cut-off: expected > 0 Hz, got {}",
                     config.force.derivative_cutoff_hz);
  if (reference_) player_ = std::make_unique<ReferencePlayer>(*reference_, config.playback);
}

void TrainingGuidance::reset() noexcept {
  if (player_) player_->restart();
  fade_ = 1.0;
  previous_mode_ = mode_;
  contact_weight_ = 0.0;
  have_error_ = false;
  error_rate_.setZero();
  cue_ = {};
  cue_index_.store(-1.0, std::memory_order_relaxed);
}

void TrainingGuidance::startTrial(double t_s) noexcept {
  reset();
  trial_start_s_ = t_s;
}

void TrainingGuidance::switchMode(TrainingMode mode) noexcept {
  if (mode == mode_) return;
  if (!reference_ && mode != TrainingMode::kBasic && !isMentored(mode)) return;  // nothing to guide toward
  // A switch during a fade starts from the mode that dominates now.
  previous_mode_ = fade_ >= 0.5 ? mode_ : previous_mode_;
  mode_ = mode;
  fade_ = config_.crossfade_s > 0.0 ? 0.0 : 1.0;
}

bool TrainingGuidance::setParameter(int parameter, double value) noexcept {
  switch (parameter) {
    case kParameterMode: {
      const int m = static_cast<int>(value);
      if (m < 0 || m > 2) return false;
      switchMode(static_cast<TrainingMode>(m));
      return true;
    }
    case kParameterRestartTrial: restart_pending_ = true; return true;
    default: return false;
  }
}

Vec3 TrainingGuidance::modeForce(TrainingMode mode, const PenState& pen, const Vec3& force_error) const noexcept {
  switch (mode) {
    case TrainingMode::kBasic: return Vec3::Zero();
    case TrainingMode::kPositionControl: {
      // In the paper plane only: the paper, not the guidance, holds the pen's height.
      Vec3 f = config_.position.kp_N_per_m * (cue_.point.p_WT - pen.p_WT) +
               config_.position.kd_N_s_per_m * (cue_.point.v_WT - pen.v_WT);
      f.z() = 0.0;
      return cue_.weight * f;
    }
    case TrainingMode::kForceControl:
      return cue_.weight * contact_weight_ * (config_.force.kp * force_error + config_.force.kd_s * error_rate_);
    // The live expert's coupling guides in a mentored mode, not the recorded reference.
    case TrainingMode::kMentorObserve:
    case TrainingMode::kMentorPosition:
    case TrainingMode::kMentorForce:
    case TrainingMode::kMentorBilateral: return Vec3::Zero();
  }
  return Vec3::Zero();
}

Vec3 TrainingGuidance::compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept {
  if (restart_pending_) {
    startTrial(pen.t_s);
    restart_pending_ = false;
  }
  if (!player_) return Vec3::Zero();
  const double dt = std::max(dt_s, 1e-9);
  cue_ = player_->at(pen.t_s - trial_start_s_, pen.p_WT);
  cue_index_.store(cue_.phase == ReferenceCue::Phase::kBefore ? -1.0 : cue_.index, std::memory_order_relaxed);

  // The force error against the expert's profile at this step, and its filtered rate. The
  // user's force is the device's force sensor where it has one, else the renderer's.
  const Vec3 f_user = pen.has_force ? pen.f_measured_W : contact.f_on_paper_W;
  const Vec3 error = cue_.point.f_W - f_user;
  if (have_error_) {
    const double alpha = dt / (dt + 1.0 / (2.0 * std::numbers::pi * config_.force.derivative_cutoff_hz));
    error_rate_ += alpha * ((error - last_error_) / dt - error_rate_);
  }
  last_error_ = error;
  have_error_ = true;

  // ALPHA fades out while the pen is off the paper, and back in on touch-down.
  const double lift_step = config_.lift_fade_s > 0.0 ? dt / config_.lift_fade_s : 1.0;
  contact_weight_ = std::clamp(contact_weight_ + (contact.in_contact ? lift_step : -lift_step), 0.0, 1.0);

  // Cross-fade between the previous and the current mode.
  const Vec3 current = modeForce(mode_, pen, error);
  if (fade_ >= 1.0) return current;
  fade_ = std::min(1.0, fade_ + dt / config_.crossfade_s);
  return fade_ * current + (1.0 - fade_) * modeForce(previous_mode_, pen, error);
}

}  // namespace hattr::guidance
