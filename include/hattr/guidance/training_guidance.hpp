#pragma once
/// The training strategies' force laws as one guidance controller on the servo thread. The
/// paper's three:
///   BASIC     no assistance;
///   PCONTROL  PD position guidance toward the reference, in the paper plane:
///             F = Kp·(x_ref − x) + Kd·(v_ref − v), paper defaults 0.35 N/mm and 0.17 N·s/mm;
///   ALPHA     PD force guidance from the haptic profile, per axis:
///             F = Kp·e + Kd·ė, e = f_expert(t) − f_user(t), paper defaults 0.5 and 0.1 s,
///             the derivative low-pass filtered.
/// and the field's since (issue 36; each with its source in docs/training_modes.md):
///   CHANNEL             a haptic channel: no force within a tube around the reference path, a
///                       spring and damper toward it outside (in the plane);
///   ERROR-AUGMENTATION  a force that amplifies the deviation from the reference, saturated;
///   NOISE               a band-limited random force in the plane, seeded per trial;
///   PLAYBACK            the expert's force played open-loop ("record and play");
/// and three scheduled strategies, a law above with a gain the session sets before each trial
/// from the trials before it (strategy_schedule.hpp):
///   FADING              PCONTROL or ALPHA with a gain falling over trials, or with performance;
///   ASSIST-AS-NEEDED    PCONTROL or ALPHA with a gain adapted to the error, with forgetting;
///   PARTIAL-THEN-FULL   CHANNEL for the first trials, then PCONTROL.
/// Mode switches cross-fade the force (default 100 ms). Gains are clamped to what the device
/// renders passively together with the paper (clampGains). strategy_catalog.hpp describes every
/// strategy and its parameters. See docs/training_modes.md.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/device_limits.hpp"
#include "hattr/core/pen_state.hpp"
#include "hattr/core/guidance_controller.hpp"
#include "hattr/core/units.hpp"
#include "hattr/guidance/reference.hpp"

namespace hattr::guidance {

/// The paper's three modes, then hattr's mentored modes: in these an expert at another station
/// writes live and the force comes over the network from their pen (net::MentorCoupling, one
/// mode per coupling, in net::Coupling's order; docs/mentoring.md). TrainingGuidance renders no
/// force for a mentored mode: the trial's live guidance does.
enum class TrainingMode : int {
  kBasic = 0,
  kPositionControl = 1,
  kForceControl = 2,
  kMentorObserve = 3,
  kMentorPosition = 4,
  kMentorForce = 5,
  kMentorBilateral = 6,
  kChannel = 7,
  kErrorAugmentation = 8,
  kNoise = 9,
  kPlayback = 10,
  kFading = 11,
  kAssistAsNeeded = 12,
  kPartialThenFull = 13,
};
/// The last mode (for loops over every mode).
inline constexpr TrainingMode kLastMode = TrainingMode::kPartialThenFull;

/// Where users see them: the paper's "BASIC", "PCONTROL", "ALPHA"; "MENTOR-OBSERVE",
/// "MENTOR-POSITION", "MENTOR-FORCE", "MENTOR-BILATERAL"; "CHANNEL", "ERROR-AUGMENTATION",
/// "NOISE", "PLAYBACK"; "FADING", "ASSIST-AS-NEEDED", "PARTIAL-THEN-FULL".
std::string_view modeName(TrainingMode mode);
/// The names of modeName in any case; throws InputError listing them otherwise.
TrainingMode parseMode(std::string_view text);
/// modeName as people type it, in lower case ("error-augmentation"): the CLI's, Python's and
/// `hattr strategies`' spelling.
std::string strategyName(TrainingMode mode);
/// A mentored mode: a live expert's pen guides (the MENTOR-... modes).
[[nodiscard]] constexpr bool isMentored(TrainingMode mode) noexcept {
  return static_cast<int>(mode) >= static_cast<int>(TrainingMode::kMentorObserve) &&
         static_cast<int>(mode) <= static_cast<int>(TrainingMode::kMentorBilateral);
}
/// A mode whose force law needs the expert's reference (all but BASIC and the mentored ones).
[[nodiscard]] constexpr bool needsReference(TrainingMode mode) noexcept {
  return mode != TrainingMode::kBasic && !isMentored(mode);
}
/// A scheduled strategy: between trials, the session chooses its law and gain for the next
/// trial from the trials before it (guidance::scheduleTrial).
[[nodiscard]] constexpr bool isScheduled(TrainingMode mode) noexcept {
  return mode == TrainingMode::kFading || mode == TrainingMode::kAssistAsNeeded ||
         mode == TrainingMode::kPartialThenFull;
}

struct PositionGains {
  double kp_N_per_m = units::newtonsPerMillimetreToSi(0.35);            ///< 350 N/m
  double kd_N_s_per_m = units::newtonSecondsPerMillimetreToSi(0.17);     ///< 170 N·s/m
};

struct ForceGains {
  double kp = 0.5;                     ///< force error gain (dimensionless)
  double kd_s = 0.1;                   ///< force-error-rate gain [s]
  double derivative_cutoff_hz = 20.0;  ///< first-order low-pass on ė
};

/// CHANNEL: a tube of half-width `half_width_m` around the reference path (the nearest
/// reference point within `search_s` of the cue, at most kMaxChannelReach samples either side);
/// outside it a spring and damper toward the tube's wall, in the paper plane.
inline constexpr std::size_t kMaxChannelReach = 1000;  ///< a tick's search: at most 2001 points
struct ChannelGains {
  double half_width_m = 0.002;                                          ///< 2 mm
  double kp_N_per_m = units::newtonsPerMillimetreToSi(0.35);            ///< the paper's PCONTROL Kp
  double kd_N_s_per_m = 0.0;                                            ///< across the wall
  double search_s = 0.5;   ///< the path searched: this long before and after the cue
};

/// ERROR-AUGMENTATION: F = gain·sat(x − x_ref) in the paper plane (a negative spring), the
/// deviation saturated at `saturation_m`, so the force never exceeds gain·saturation_m.
struct AugmentationGains {
  double gain_N_per_m = units::newtonsPerMillimetreToSi(0.1);   ///< 100 N/m
  double saturation_m = 0.01;                                    ///< 10 mm
};

/// NOISE: a Gaussian force in the plane, each axis white noise through a first-order low-pass
/// at `cutoff_hz`, scaled to `rms_N`; the same trial seed gives the same force.
struct NoiseConfig {
  double rms_N = 0.3;
  double cutoff_hz = 5.0;
  std::uint64_t seed = 1;   ///< set per trial (the session: from the trial's seed)
};

/// PLAYBACK: the expert's force on the paper, times `gain`, pushed onto the pen open-loop.
struct PlaybackGains {
  double gain = 1.0;
};

/// FADING: the base law's gain, from start_gain to end_gain, falling linearly over the first
/// `trials` guided trials (by = kTrials), or by `step` after each trial whose tracking error was
/// at most `threshold_m` (by = kPerformance).
struct FadingConfig {
  enum class By : int { kTrials = 0, kPerformance = 1 };
  TrainingMode base = TrainingMode::kPositionControl;  ///< PCONTROL or ALPHA
  By by = By::kTrials;
  double start_gain = 1.0;
  double end_gain = 0.0;
  double trials = 10.0;        ///< kTrials: the gain reaches end_gain at this guided trial
  double step = 0.2;           ///< kPerformance: the gain's fall after a good trial
  double threshold_m = 0.002;  ///< kPerformance: a good trial's tracking error at most [m]
};

/// ASSIST-AS-NEEDED (Emken, Benitez & Reinkensmeyer 2007): g₁ = start_gain, then
/// g_{n+1} = clamp(forgetting·g_n + error_gain·max(0, e_n − deadband), 0, 1), e_n the trial's
/// tracking error: assistance fades by the forgetting factor and grows with the error.
struct AssistAsNeededConfig {
  TrainingMode base = TrainingMode::kPositionControl;  ///< PCONTROL or ALPHA
  double start_gain = 1.0;
  double forgetting = 0.9;
  double error_gain_per_m = 50.0;   ///< 0.05 per mm of tracking error
  double deadband_m = 0.0005;       ///< errors up to this are the trainee's own variability
};

/// PARTIAL-THEN-FULL (Teranishi et al. 2017): CHANNEL (partial guidance) for the first
/// `partial_trials` guided trials, then PCONTROL (full guidance), each with its own parameters.
struct PartialThenFullConfig {
  double partial_trials = 5.0;
};

/// A scheduled strategy's law and gain for one trial (set by the session before the trial).
struct ScheduledLaw {
  TrainingMode law = TrainingMode::kPositionControl;  ///< PCONTROL, ALPHA or CHANNEL
  double gain = 1.0;                                  ///< 0 to 1
};

struct GuidanceConfig {
  TrainingMode mode = TrainingMode::kBasic;
  PositionGains position;
  ForceGains force;
  ChannelGains channel;
  AugmentationGains augmentation;
  NoiseConfig noise;
  PlaybackGains playback_force;
  FadingConfig fading;
  AssistAsNeededConfig assist;
  PartialThenFullConfig partial_then_full;
  ScheduledLaw scheduled;      ///< a scheduled mode's law and gain in this trial
  PlaybackConfig playback;
  double crossfade_s = 0.1;    ///< mode switches fade over this long
  double lift_fade_s = 0.05;   ///< ALPHA fades out over this long while the pen is off the paper
};

/// What the world renders on the same axes as the guidance (for the passivity clamp).
struct WorldImpedance {
  double normal_stiffness_N_per_m = 600.0;
  double normal_damping_N_s_per_m = 0.1;
  double tangential_stiffness_N_per_m = 500.0;
};

/// Clamps PCONTROL's Kp, Kd and ALPHA's Kp, Kd so that guidance plus world stay passive on
/// the device (hattr::clampImpedance). ALPHA acts through the paper: its effective stiffness
/// is Kp·K and its effective damping Kp·C + Kd·K on each axis. CHANNEL's spring and damper
/// are clamped as PCONTROL's; ERROR-AUGMENTATION's gain, a negative spring, to the stiffness a
/// positive one may have. Returns one line per changed value, each starting with the mode's
/// name ("PCONTROL Kd 170 N·s/m -> 0.46 N·s/m: ...").
std::vector<std::string> clampGains(GuidanceConfig& config, const DeviceLimits& limits, double rate_hz,
                                    const WorldImpedance& world);

/// Mailbox parameters (servo::ServoCommand::kSetGuidanceParameter).
enum GuidanceParameter : int {
  kParameterMode = 1,          ///< value: a TrainingMode as a number; cross-fades (a scheduled mode: only the trial's own)
  kParameterRestartTrial = 2,  ///< the trial starts at this tick
};

class TrainingGuidance final : public GuidanceController {
 public:
  /// `reference` may be null only for BASIC-only use. Throws InputError for bad settings.
  TrainingGuidance(std::shared_ptr<const ReferenceTrajectory> reference, const GuidanceConfig& config);

  Vec3 compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept override;
  bool setParameter(int parameter, double value) noexcept override;
  void reset() noexcept override;

  /// The trial starts at loop time t_s (before running; or through kParameterRestartTrial).
  void startTrial(double t_s) noexcept;
  /// Switches mode with a cross-fade (servo thread, or before running).
  void switchMode(TrainingMode mode) noexcept;

  [[nodiscard]] TrainingMode mode() const noexcept { return mode_; }
  [[nodiscard]] const ReferenceCue& lastCue() const noexcept { return cue_; }
  /// The reference's fractional index the guidance played at its last tick, for a display on
  /// another thread (any thread; a relaxed atomic). Negative before the trial starts.
  [[nodiscard]] double cueIndex() const noexcept { return cue_index_.load(std::memory_order_relaxed); }
  [[nodiscard]] const GuidanceConfig& config() const noexcept { return config_; }

 private:
  Vec3 modeForce(TrainingMode mode, const PenState& pen, const Vec3& force_error) const noexcept;
  Vec3 channelForce(const PenState& pen) const noexcept;
  /// NOISE's filtered force, one step (once per tick, whichever mode shows it).
  void stepNoise(double dt_s) noexcept;
  void restartNoise() noexcept;

  std::shared_ptr<const ReferenceTrajectory> reference_;
  GuidanceConfig config_;
  std::unique_ptr<ReferencePlayer> player_;
  TrainingMode mode_;
  TrainingMode previous_mode_;
  double fade_ = 1.0;                // weight of mode_ against previous_mode_
  double contact_weight_ = 0.0;      // ALPHA's fade while the pen is off the paper
  double trial_start_s_ = 0.0;
  bool restart_pending_ = false;
  bool have_error_ = false;
  Vec3 last_error_ = Vec3::Zero();
  Vec3 error_rate_ = Vec3::Zero();   // filtered ė
  ReferenceCue cue_;
  std::atomic<double> cue_index_{-1.0};  // cue_.index while running, else -1 (cueIndex())
  std::uint64_t noise_state_ = 0;        // NOISE's generator (splitmix64), from config_.noise.seed
  Vec3 noise_ = Vec3::Zero();            // NOISE's filtered force
};

}  // namespace hattr::guidance
