#include "hattr/guidance/training_guidance.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>
#include <fmt/ranges.h>

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
    case TrainingMode::kChannel: return "CHANNEL";
    case TrainingMode::kErrorAugmentation: return "ERROR-AUGMENTATION";
    case TrainingMode::kNoise: return "NOISE";
    case TrainingMode::kPlayback: return "PLAYBACK";
    case TrainingMode::kFading: return "FADING";
    case TrainingMode::kAssistAsNeeded: return "ASSIST-AS-NEEDED";
    case TrainingMode::kPartialThenFull: return "PARTIAL-THEN-FULL";
  }
  return "?";
}

TrainingMode parseMode(std::string_view text) {
  std::string upper(text);
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return std::toupper(c); });
  std::vector<std::string> names;
  for (int m = 0; m <= static_cast<int>(kLastMode); ++m) {
    const auto mode = static_cast<TrainingMode>(m);
    if (upper == modeName(mode)) return mode;
    names.push_back(strategyName(mode));
  }
  throw InputError(fmt::format("mode: expected one of {}, got \"{}\"", fmt::join(names, ", "), text));
}

std::string strategyName(TrainingMode mode) {
  std::string name(modeName(mode));
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  return name;
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

  // CHANNEL's wall is PCONTROL's spring and damper, outside the tube.
  const auto channel = clampImpedance(config.channel.kp_N_per_m, config.channel.kd_N_s_per_m,
                                      {.stiffness_name = "CHANNEL Kp", .damping_name = "CHANNEL Kd",
                                       .k_other_N_per_m = world.tangential_stiffness_N_per_m},
                                      limits, rate_hz);
  changes.insert(changes.end(), channel.begin(), channel.end());
  // ERROR-AUGMENTATION is a negative spring: no larger than a positive one may be.
  double augmentation = config.augmentation.gain_N_per_m;
  double no_damping = 0.0;
  const auto augmented = clampImpedance(augmentation, no_damping,
                                        {.stiffness_name = "ERROR-AUGMENTATION gain", .damping_name = "-",
                                         .k_other_N_per_m = world.tangential_stiffness_N_per_m},
                                        limits, rate_hz);
  config.augmentation.gain_N_per_m = augmentation;
  changes.insert(changes.end(), augmented.begin(), augmented.end());
  return changes;
}

TrainingGuidance::TrainingGuidance(std::shared_ptr<const ReferenceTrajectory> reference, const GuidanceConfig& config)
    : reference_(std::move(reference)), config_(config), mode_(config.mode), previous_mode_(config.mode) {
  HATTR_THROW_UNLESS(reference_ || !needsReference(config.mode),
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
  check(config.channel.half_width_m, "CHANNEL half-width");
  check(config.channel.kp_N_per_m, "CHANNEL Kp");
  check(config.channel.kd_N_s_per_m, "CHANNEL Kd");
  check(config.channel.search_s, "CHANNEL search");
  HATTR_THROW_UNLESS(config.channel.search_s <= 10.0, "guidance: CHANNEL search: expected at most 10 s, got {}",
                     config.channel.search_s);
  check(config.augmentation.gain_N_per_m, "ERROR-AUGMENTATION gain");
  check(config.augmentation.saturation_m, "ERROR-AUGMENTATION saturation");
  check(config.noise.rms_N, "NOISE rms");
  check(config.playback_force.gain, "PLAYBACK gain");
  HATTR_THROW_UNLESS(std::isfinite(config.noise.cutoff_hz) && config.noise.cutoff_hz > 0.0,
                     "guidance: NOISE cut-off: expected > 0 Hz, got {}", config.noise.cutoff_hz);
  // A scheduled mode plays one of the plain reference laws, at most at full strength.
  const TrainingMode law = config.scheduled.law;
  HATTR_THROW_UNLESS(law == TrainingMode::kPositionControl || law == TrainingMode::kForceControl ||
                         law == TrainingMode::kChannel,
                     "guidance: a scheduled strategy's law: expected PCONTROL, ALPHA or CHANNEL, got {}", modeName(law));
  HATTR_THROW_UNLESS(std::isfinite(config.scheduled.gain) && config.scheduled.gain >= 0.0 && config.scheduled.gain <= 1.0,
                     "guidance: a scheduled strategy's gain: expected 0 to 1, got {}", config.scheduled.gain);
  HATTR_THROW_UNLESS(config.force.derivative_cutoff_hz > 0.0, "guidance: ALPHA derivative cut-off: expected > 0 Hz, got {}",
                     config.force.derivative_cutoff_hz);
  if (reference_) player_ = std::make_unique<ReferencePlayer>(*reference_, config.playback);
  restartNoise();
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
  restartNoise();
}

void TrainingGuidance::startTrial(double t_s) noexcept {
  reset();
  trial_start_s_ = t_s;
}

void TrainingGuidance::switchMode(TrainingMode mode) noexcept {
  if (mode == mode_) return;
  if (!reference_ && needsReference(mode)) return;  // nothing to guide toward
  // A switch during a fade starts from the mode that dominates now.
  previous_mode_ = fade_ >= 0.5 ? mode_ : previous_mode_;
  mode_ = mode;
  fade_ = config_.crossfade_s > 0.0 ? 0.0 : 1.0;
}

bool TrainingGuidance::setParameter(int parameter, double value) noexcept {
  switch (parameter) {
    case kParameterMode: {
      const int m = static_cast<int>(value);
      if (m < 0 || m > static_cast<int>(kLastMode) || isMentored(static_cast<TrainingMode>(m))) return false;
      // A scheduled mode plays the law and gain set for the trial's own mode, and no other.
      if (isScheduled(static_cast<TrainingMode>(m)) && static_cast<TrainingMode>(m) != config_.mode) return false;
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
    case TrainingMode::kChannel: return cue_.weight * channelForce(pen);
    case TrainingMode::kErrorAugmentation: {
      // Away from the reference point, in the plane, no more than gain × saturation.
      Vec3 e = pen.p_WT - cue_.point.p_WT;
      e.z() = 0.0;
      const double size = e.norm();
      const double limit = config_.augmentation.saturation_m;
      if (size > limit) e *= limit / size;
      return cue_.weight * config_.augmentation.gain_N_per_m * e;
    }
    case TrainingMode::kNoise: return cue_.weight * noise_;  // fades out with the reference, as the others
    case TrainingMode::kPlayback: return cue_.weight * config_.playback_force.gain * cue_.point.f_W;
    // The law the session chose for this trial, at its gain (the law is never a scheduled one).
    case TrainingMode::kFading:
    case TrainingMode::kAssistAsNeeded:
    case TrainingMode::kPartialThenFull:
      return config_.scheduled.gain * modeForce(config_.scheduled.law, pen, force_error);
  }
  return Vec3::Zero();
}

Vec3 TrainingGuidance::channelForce(const PenState& pen) const noexcept {
  // The nearest point of the path within the search window around the cue, in the plane.
  const ReferenceTrajectory& path = *reference_;
  const std::size_t reach =
      std::min(kMaxChannelReach, static_cast<std::size_t>(config_.channel.search_s / path.dt_s()));
  const auto at = static_cast<std::size_t>(std::max(0.0, cue_.index));
  const std::size_t first = at > reach ? at - reach : 0;
  const std::size_t last = std::min(path.size() - 1, at + reach);
  double nearest_sq = std::numeric_limits<double>::infinity();
  Eigen::Vector2d nearest = Eigen::Vector2d::Zero();
  for (std::size_t k = first; k <= last; ++k) {
    const Eigen::Vector2d q = path[k].p_WT.head<2>();
    const double d_sq = (pen.p_WT.head<2>() - q).squaredNorm();
    if (d_sq < nearest_sq) {
      nearest_sq = d_sq;
      nearest = q;
    }
  }
  // Inside the tube, nothing; outside, a spring and damper toward its wall.
  const double distance = std::sqrt(nearest_sq);
  if (!(distance > config_.channel.half_width_m)) return Vec3::Zero();
  const Eigen::Vector2d out = (pen.p_WT.head<2>() - nearest) / distance;
  const double outward_speed = out.dot(pen.v_WT.head<2>());
  const Eigen::Vector2d f = -(config_.channel.kp_N_per_m * (distance - config_.channel.half_width_m) +
                              config_.channel.kd_N_s_per_m * outward_speed) * out;
  return Vec3(f.x(), f.y(), 0.0);
}

namespace {

/// splitmix64: the next 64 random bits.
std::uint64_t nextBits(std::uint64_t& state) noexcept {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/// A uniform number in (0, 1].
double uniformOpen(std::uint64_t& state) noexcept {
  return (static_cast<double>(nextBits(state) >> 11) + 1.0) * 0x1.0p-53;
}

}  // namespace

void TrainingGuidance::restartNoise() noexcept {
  noise_state_ = config_.noise.seed;
  noise_.setZero();
}

void TrainingGuidance::stepNoise(double dt_s) noexcept {
  // Two standard normals (Box–Muller), through a first-order low-pass whose output has the
  // asked RMS: a white input of variance σ² gives σ²·α/(2 − α).
  const double radius = std::sqrt(-2.0 * std::log(uniformOpen(noise_state_)));
  const double angle = 2.0 * std::numbers::pi * uniformOpen(noise_state_);
  const double alpha = dt_s / (dt_s + 1.0 / (2.0 * std::numbers::pi * config_.noise.cutoff_hz));
  const double input_sd = config_.noise.rms_N * std::sqrt((2.0 - alpha) / alpha);
  const Vec3 white(radius * std::cos(angle), radius * std::sin(angle), 0.0);
  noise_ += alpha * (input_sd * white - noise_);
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

  if (mode_ == TrainingMode::kNoise || (fade_ < 1.0 && previous_mode_ == TrainingMode::kNoise)) stepNoise(dt);

  // Cross-fade between the previous and the current mode.
  const Vec3 current = modeForce(mode_, pen, error);
  if (fade_ >= 1.0) return current;
  fade_ = std::min(1.0, fade_ + dt / config_.crossfade_s);
  return fade_ * current + (1.0 - fade_) * modeForce(previous_mode_, pen, error);
}

}  // namespace hattr::guidance
