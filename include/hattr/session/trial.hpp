#pragma once
/// One trial through the whole pipeline: a device (opened by URI; a simulated pen is driven
/// by a hand script), the paper, the training mode's guidance, the safety path, the servo
/// loop on either clock, and the recorder. The same code records an expert and runs a
/// trainee's trial; `hattr record`, `hattr train` and the study runner call it.

#include <atomic>
#include <map>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/core/guidance_controller.hpp"
#include "hattr/device/device.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/session/recorder.hpp"
#include "hattr/session/trial_physics.hpp"

namespace hattr::session {

/// The clock a trial asks for. kSimulated is honoured only by devices that can be simulated
/// (sim://pen, the sim and replay plugins); any other device runs the trial in real time, on
/// the loop's thread or the device's own clock (TrialResult::clock says which ran).
enum class Clock { kSimulated, kRealTime };
/// The clock named "sim" or "real" (as the CLI and Python spell it); InputError otherwise.
Clock parseClock(std::string_view name);

/// What stays the same from trial to trial: the device model, the paper (built once: the
/// relief and texture take a moment), the rate. Clamps are applied on construction.
class TrialEnvironment {
 public:
  /// Throws InputError for a bad URI, world or rate. Opens nothing: a simulated pen's limits are
  /// known from its URI and bound here; any other device's are bound when its first trial opens
  /// it (TrialRun calls bindLimits), so a device is opened once per trial, never to be asked.
  TrialEnvironment(std::string device_uri, render::WorldConfig world, double rate_hz = 1000.0);

  /// The device's limits: the world clamped to what it renders passively, the paper built for it.
  /// The first call binds them; later calls with the same limits do nothing, and other limits
  /// (another device behind the same URI) throw InputError, the environment unchanged.
  void bindLimits(const DeviceLimits& limits);
  /// Whether the device's limits are known (a simulated pen's always; another device's once a
  /// trial has opened it). limits(), paper() and worldClamps() need them (InvariantError before).
  [[nodiscard]] bool limitsBound() const noexcept { return paper_ != nullptr; }

  [[nodiscard]] const std::string& deviceUri() const noexcept { return device_uri_; }
  [[nodiscard]] const DeviceLimits& limits() const;
  [[nodiscard]] double rate_hz() const noexcept { return rate_hz_; }
  /// The world configuration: as given until the limits are bound, then clamped to them.
  [[nodiscard]] const render::WorldConfig& world() const noexcept { return world_; }
  [[nodiscard]] render::PaperRenderer& paper();
  /// The paper's relief, known before the limits (the clamps change the paper's contact, not it).
  [[nodiscard]] const render::HeightField& relief() const noexcept { return relief_; }
  /// The relief a simulated hand's reach is measured from (SettlingHand): null for one that stays
  /// within kHandFlatRelief_m of the writing plane, as paper's grain does, where the plane is as
  /// good (an error under 1.3 % of the fingers' 8 mm ease, and no look-up in the hand's sub-steps).
  [[nodiscard]] const render::HeightField* handRelief() const noexcept { return hand_relief_ ? &relief_ : nullptr; }
  static constexpr double kHandFlatRelief_m = 1e-4;
  /// What the passivity bounds changed in the world configuration.
  [[nodiscard]] const std::vector<std::string>& worldClamps() const;
  /// The world's impedance on the guidance's axes (for clampGains).
  [[nodiscard]] guidance::WorldImpedance impedance() const noexcept;
  /// What a trial's recording is judged against (TrialResult::physics): the paper's thickness.
  [[nodiscard]] PhysicalBounds physicalBounds() const noexcept {
    return PhysicalBounds{.paper_thickness_m = world_.paper.thickness_m};
  }

 private:
  std::string device_uri_;
  render::WorldConfig world_;
  double rate_hz_;
  DeviceLimits limits_;
  std::vector<std::string> world_clamps_;
  render::HeightField relief_;  ///< built at construction; the paper gets a copy once the limits are bound
  bool hand_relief_ = false;     ///< the relief departs from the plane by more than kHandFlatRelief_m
  std::unique_ptr<render::PaperRenderer> paper_;
};

/// A request to end a trial from another thread (the studio's stop key): request() may be
/// called from any thread, at any time; a real-time trial watching it ends within a few ms
/// with TrialResult::end_reason "stopped". A simulated trial ignores it (its end must depend
/// on its samples alone). Must outlive the trial that watches it.
class TrialStop {
 public:
  void request() noexcept { requested_.store(true, std::memory_order_release); }
  void reset() noexcept { requested_.store(false, std::memory_order_release); }
  [[nodiscard]] bool requested() const noexcept { return requested_.load(std::memory_order_acquire); }

 private:
  std::atomic<bool> requested_{false};
};

/// Why a trial ended (TrialResult::end_reason and the profile's metadata `end_reason`).
inline constexpr std::string_view kEndPenLifted = "pen lifted";
inline constexpr std::string_view kEndMaximumDuration = "maximum duration";
inline constexpr std::string_view kEndStopped = "stopped";
inline constexpr std::string_view kEndFailed = "failed";

struct TrialResult;

/// The guidance of a mentored mode's trial (guidance::isMentored): an expert at another
/// station, or a simulated one, writes live, and a coupling turns their pen into this trial's
/// force (net::makeStudyMentor implements it; the session module does not depend on the
/// network). One trial at a time; main-thread calls, the stage runs on the servo thread.
class LiveGuidance {
 public:
  virtual ~LiveGuidance() = default;
  /// The shortest settle phase that lets the link come up and the coupling fade in [s].
  [[nodiscard]] virtual double minimumSettle_s() const noexcept = 0;
  /// Before the trial's loop starts: the guidance stage for a trial of `mode` (a mentored one)
  /// on `environment`, with `settle_s` before the trial's clock starts; `seed` makes an emulated
  /// link repeatable. Valid until endTrial. Throws InputError or Error.
  virtual GuidanceController& beginTrial(guidance::TrainingMode mode, const TrialEnvironment& environment,
                                         double settle_s, std::uint64_t seed) = 0;
  /// Empty once the link to the expert is up; otherwise why not, for people ("no answer from
  /// the expert's station at ..."). Checked when the settle phase ends: a trial without its
  /// mentor fails there, before anything is recorded. Any thread, while the trial runs.
  [[nodiscard]] virtual std::string unavailable() const = 0;
  /// After the loop stopped: ends the link's session; a link lost during the trial counts in
  /// TrialResult::mentor_link_faults (a disturbed trial). Returns what
  /// goes into the recording's metadata (the coupling, the link, the energies).
  virtual std::map<std::string, std::string> endTrial(TrialResult& result) = 0;
};

struct TrialSetup {
  guidance::GuidanceConfig guidance;                            ///< mode, gains, indexing
  std::shared_ptr<const guidance::ReferenceTrajectory> reference;  ///< null for BASIC without one
  ProfileMetadata metadata;                                     ///< subject, skill, ...; mode etc. are added
  /// The maximum duration [s]: the trial ends here at the latest (recorded). Without an end
  /// rule (pen_up_end_s = 0) every trial lasts exactly this long.
  double duration_s = 1.0;
  /// The end rule: > 0, the trial ends once the pen has been up (out of contact with the paper)
  /// for this long [s] after writing began (the first pen-down); the recording ends with that
  /// sample. 0: off. Decided sample by sample, so a simulated trial ends at the same tick
  /// whatever the loop's chunking.
  double pen_up_end_s = 0.0;
  /// Real-time trials only: ends the trial when requested (null: nothing to watch).
  const TrialStop* stop = nullptr;
  /// Before the trial: the loop runs this long with the hand holding the pen 3 mm above its
  /// first point, so the safety path's ramp-in is complete before the pen meets the paper.
  /// Not recorded; the trial's clock starts after it. Must be at least the ramp time.
  double settle_s = 0.3;
  Clock clock = Clock::kSimulated;
  RecordTrigger trigger = RecordTrigger::kCommand;
  /// Simulated clock: a host stall of `injected_stall_s` at this time of the trial's clock
  /// (rehearsing a study's disturbed-trial policy); negative: none.
  double inject_stall_at_s = -1.0;
  double injected_stall_s = 0.03;
  /// A mentored mode's guidance (required for one, unused otherwise); must outlive the trial.
  LiveGuidance* live_guidance = nullptr;
  std::uint64_t live_seed = 1;   ///< passed to LiveGuidance::beginTrial
  /// Once the trial's device is open and its limits bound, before the guidance and the loop are
  /// built: refuses a trial the device cannot render by throwing InputError (a reference too strong
  /// or outside its workspace: checkRenderable). Null: no check.
  std::function<void(const DeviceLimits&)> check_device;
};

struct TrialResult {
  HapticProfile profile;               ///< f_user and f_guide recorded separately
  std::vector<std::string> clamps;     ///< every gain and world clamp applied
  std::uint64_t ticks = 0;
  std::uint64_t missed_samples = 0;
  std::uint64_t overruns = 0;
  std::uint64_t faults = 0;
  std::uint64_t link_faults = 0;       ///< times the device (a network link) was lost
  std::uint64_t mentor_link_faults = 0;  ///< times a mentored trial's link to the expert was lost
  std::uint64_t stalls = 0;            ///< loop or device-clock stalls (force zeroed)
  double max_period_error_s = 0.0;     ///< the largest |period − nominal| of a real-time run [s]
  /// What the recording did that a good trial does not (the pen through the paper, the device
  /// at its force limit, the pen outside the workspace), judged against TrialSetup::bounds.
  PhysicalEvents physics;
  std::string clock;                   ///< the clock that ran it: simulated, real-time, device
  /// Why it ended: "pen lifted", "maximum duration", "stopped" or "failed" (kEnd...). Also in
  /// the profile's metadata as `end_reason`, with `writing_begin_s` and `writing_end_s`: the
  /// profile times [s] of the first pen-down and of the last pen-up (the last sample's time if
  /// the pen was still down), written with "{}" so they read back exactly; both absent when the
  /// pen never touched the paper.
  std::string end_reason;
  double writing_begin_s = -1.0;       ///< profile time of the first pen-down [s]; < 0: none
  double writing_end_s = -1.0;         ///< profile time of the last pen-up [s]; < 0: none
  /// Empty when the trial ran to its end; otherwise why it was stopped early (a device fault,
  /// a lost link, a stalled device clock), with the device's own reason. The profile then
  /// holds what was recorded up to the failure (empty if it failed while settling) and its
  /// metadata says "failed".
  std::string failure;
};

/// The hand during a trial's settle phase: the pen held lifted (at least 3 mm) above the
/// script's first point at rest — or, with `follow`, above wherever a live hand is — and after
/// `settle_s` the script (on the trial's clock, or unchanged when following).
class SettlingHand final : public device::HandScript {
 public:
  /// `relief`: the paper under the hand (null: flat); each command's surface_z_m is its height
  /// under the target, where the fingers' reach is measured from. Must outlive the hand.
  SettlingHand(device::HandScript& script, double settle_s, bool follow = false,
               const render::HeightField* relief = nullptr);
  device::HandCommand command(double t_s) noexcept override;
  void rewind() noexcept override { script_.rewind(); }

 private:
  device::HandScript& script_;
  double settle_s_;
  bool follow_;
  device::HandCommand lifted_;
  const render::HeightField* relief_;
};

/// The device a trial uses: the URI's device; a simulated pen starts 3 mm above where the
/// hand begins. Throws InputError for a bad URI.
std::unique_ptr<device::Device> openTrialDevice(const std::string& uri, device::HandScript& hand);

/// Clamps the gains of every mode (a trial may switch modes) to what the environment renders
/// passively; returns the world's clamps and those of the mode in use, for the report.
std::vector<std::string> clampTrialGains(guidance::GuidanceConfig& config, const TrialEnvironment& environment);

/// A trial recording's metadata: `base` plus the device, creation time, source, the mode,
/// indexing, speed, the gains used, the clamps and the clock.
ProfileMetadata trialMetadata(ProfileMetadata base, const TrialEnvironment& environment,
                              const guidance::GuidanceConfig& config, const std::vector<std::string>& clamps,
                              Clock clock);

/// How a trial was disturbed, for people ("2 stalls (force zeroed) · 3 missed samples · the pen
/// 186.0 mm under the paper at 1.234 s"); empty when it ran clean. Stalls, missed samples, safety
/// faults, lost device links, lost links to a mentor and physical events (TrialResult::physics)
/// disturb a trial; overruns alone (late ticks) do not, and are stored all the same.
std::string disturbanceOf(const TrialResult& result);

/// Writes the loop's counters of a trial (ticks, overruns, stalls, missed samples, safety
/// faults, lost links), its physical events and its disturbance into its recording's metadata;
/// returns the disturbance (disturbanceOf). TrialRun::finish calls it for every trial.
std::string noteLoopCounters(TrialResult& result);

/// After the recorder stopped: the trial's end reason (failed, pen lifted, `stopped`, or the
/// maximum duration), its writing span, and the recording, with these in its metadata
/// (end_reason, writing_begin_s, writing_end_s). TrialRun::finish uses it.
void noteTrialEnd(TrialResult& result, Recorder& recorder, bool stopped);

/// A trial of a hand script, as `hattr record`, `hattr train` and Python's hattr.run_trial set
/// it up. Without an expert it records (no guidance); with one it trains in `mode`.
struct ScriptedTrialOptions {
  double rate_hz = 1000.0;       ///< the servo rate the reference is resampled to [Hz]
  double tail_s = 0.3;           ///< without an end rule: recorded this long after the script [s]
  double pen_up_end_s = 0.0;     ///< > 0: the end rule (TrialSetup::pen_up_end_s) [s]
  double max_duration_s = 0.0;   ///< with the end rule: the longest trial [s] (0: 3 x the script)
  Clock clock = Clock::kSimulated;
  std::string subject;           ///< "" : "expert" when recording, "trainee" when training
  std::string skill;             ///< "" : the script's skill, else the expert's
  std::string hand_label;        ///< recorded as metadata `hand_script` (a file name)
  const HapticProfile* expert = nullptr;  ///< the reference to train against; null: record
  std::string reference_label;   ///< recorded as metadata `reference`
  guidance::TrainingMode mode = guidance::TrainingMode::kBasic;
  guidance::Indexing indexing = guidance::Indexing::kTime;
  double speed = 1.0;            ///< reference playback speed (time indexing)
  int trial = 0;                 ///< trial number recorded when training
  /// The mode's parameters by name, in the catalog's units or a choice's name
  /// (guidance::setStrategyParameters); "STRATEGY.NAME" names another strategy's (a scheduled
  /// mode's law's gains: "pcontrol.kp_N_per_mm"). A scheduled mode plays its first trial's law and gain.
  std::vector<guidance::StrategySetting> parameters;
  std::uint64_t seed = 1;        ///< NOISE's seed
};

/// The set-up of a scripted trial: its duration (the script's plus the tail, or the end rule's
/// maximum), clock, metadata, and when training, the reference and the mode's guidance. Throws
/// InputError for a bad expert profile.
TrialSetup scriptedTrialSetup(const device::ProfileHandScript& hand, const HapticProfile& script,
                              const ScriptedTrialOptions& options);

/// Runs one trial: the settle phase, then recorded until the end rule (pen_up_end_s), the
/// stop request (real time) or `duration_s`, whichever comes first. A simulated pen starts 3 mm
/// above the hand's first target. On a real-time clock the trial ends early, with
/// TrialResult::failure set, within a few ms of a device fault, a lost link or a stalled device
/// clock (the loop has already commanded zero force). Throws InputError for bad settings;
/// hattr::Error if the recording is empty.
TrialResult runTrial(TrialEnvironment& environment, const TrialSetup& setup, device::HandScript& hand);

/// The samples of `reference` resampled at the trial's rate, as the trainee's trial shows
/// it (for tests and analysis): RMS distance in the plane [m] and RMS force error [N]
/// between a trial and the reference at the same time steps.
struct TrialErrors {
  double position_rms_m = 0.0;
  double force_rms_N = 0.0;
};
TrialErrors trialErrors(const HapticProfile& trial, const guidance::ReferenceTrajectory& reference);

}  // namespace hattr::session
