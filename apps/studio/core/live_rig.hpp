#pragma once
/// The studio's live rig: a trial's pipeline built by the library (session::TrialRun, which
/// runTrial builds and reports every trial with: the set-up checked, the guidance with its
/// clamped gains or a mentor's live stage, the settling hand, the device, the paper and the
/// servo loop; the result when it ends), driven from the window instead of in one call, so the
/// GUI can watch the loop's triple buffer, post mailbox commands (mode switches) and start or
/// stop recording while a person writes. What is the rig's own: the relay that feeds the
/// recorder and arms it at the exact sample where a trial's window begins, the stop key, and
/// runTrial's watch (session::TrialWatch) run from the relay thread. With the same hand in
/// simulated time it records what runTrial records, bit for bit (tests/studio/studio_rig_test.cpp).
///
/// Threads: the GUI thread calls every member; the servo thread runs the loop; in real time
/// a relay thread takes every sample from the loop's ring and hands it to the recorder.

#include <atomic>
#include <cstdint>
#include <limits>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/core/spsc_ring.hpp"
#include "hattr/device/device.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "hattr/servo/servo_loop.hpp"
#include "hattr/session/recorder.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/session/trial_run.hpp"
#include "hattr/session/trial_watch.hpp"

namespace hattr::studio {

/// What a run records.
enum class RecordMode {
  kNone,     ///< nothing (free writing); the ring is still drained
  kCommand,  ///< between armRecording() and disarmRecording() (start/stop buttons)
  kPenDown,  ///< from the first pen-down until the pen has been up for pen_up_stop_s
  kWindow,   ///< exactly the trial: from settle_s of loop time until the end rule (pen_up_end_s)
             ///< or the maximum (settle_s + duration_s, excluded), whichever comes first
};

/// One run of the rig.
struct RunSpec {
  guidance::GuidanceConfig guidance;                               ///< mode, gains, indexing
  std::shared_ptr<const guidance::ReferenceTrajectory> reference;  ///< null: BASIC only
  ProfileMetadata metadata;                                        ///< subject, skill, ...
  RecordMode record = RecordMode::kNone;
  /// The pen is held lifted this long while the forces ramp in (at least the safety ramp,
  /// 0.25 s); the trial's clock and guidance start after it. Not recorded.
  double settle_s = 0.3;
  double duration_s = 1.0;     ///< kWindow: the trial's maximum duration [s]
  /// The end rule (session::TrialSetup::pen_up_end_s): > 0, the recording ends once the pen
  /// has been up this long [s] after writing began (the recording's first pen-down), with the
  /// sample that ends it; the recorder decides sample by sample, as in runTrial. 0: off.
  double pen_up_end_s = 0.0;
  /// kPenDown: stop after the pen is up this long [s]. With an end rule, runTrial's recorder
  /// uses pen_up_end_s here too, and so does the rig.
  double pen_up_stop_s = 1.0;
  /// During the settle phase: true, the lifted pen follows the live hand (a person moves to
  /// the start); false, it is held above the hand's first point, as runTrial does.
  bool follow_during_settle = true;
  /// A mentored mode's guidance (session::TrialSetup::live_guidance): the expert's station
  /// steers this run's force instead of TrainingGuidance. As in runTrial, the settle phase is
  /// lengthened to the mentor's minimum (spec() reports the settle used) and a mentor whose
  /// link is not up when the settle ends fails the run before anything is recorded. Must
  /// outlive the run; null for every other mode.
  session::LiveGuidance* live_guidance = nullptr;
  std::uint64_t live_seed = 1;  ///< passed to LiveGuidance::beginTrial
  /// session::TrialSetup::check_device: refuses the run once the device is open, before its loop.
  std::function<void(const DeviceLimits&)> check_device;
};

/// The rig's state, readable from the GUI thread while a run goes on.
struct RigStatus {
  bool running = false;
  bool settling = false;       ///< still in the settle phase
  bool recording = false;      ///< the recorder is taking samples
  bool window_done = false;    ///< kWindow: the trial's window is over (the end rule or the maximum)
  bool writing_over = false;   ///< the end rule ended the recording (the pen lifted long enough)
  bool stopped = false;        ///< a stop request was taken: nothing after it is recorded
  bool pen_down_done = false;  ///< kPenDown: recorded and stopped after a long pen-up
  /// The trial failed: in real time the device or the loop ended it early, as runTrial's
  /// session::TrialWatch judges it (a fault, a lost device, a stopped clock), or a mentored
  /// trial's expert was not there when the settle ended; finish() says why.
  bool failed = false;
  std::uint64_t recorded_samples = 0;
  double loop_time_s = 0.0;  ///< loop time of the newest sample the relay took
};

/// The run that records a trial set up for runTrial: its guidance, reference, metadata,
/// maximum duration, end rule and settle time, recorded from settle_s until the end rule
/// ends it or until settle_s + duration_s (kPenDown for a pen-down trigger).
/// `follow_during_settle`: true for a live hand (a person), false for a script (as runTrial).
RunSpec trialRunSpec(const session::TrialSetup& setup, bool follow_during_settle);

class LiveRig {
 public:
  LiveRig();
  ~LiveRig();
  LiveRig(const LiveRig&) = delete;
  LiveRig& operator=(const LiveRig&) = delete;

  /// Starts a run on `environment` (its paper, device URI and rate) with `hand` holding a
  /// simulated pen. Real time: starts the servo thread (RealtimePolicy::kTry) and the relay
  /// thread. Simulated: nothing moves until advanceSimulated(). A run in progress is
  /// finished first and its recording discarded. `environment` and `hand` must outlive the
  /// run. Throws InputError for bad settings (as runTrial).
  void start(session::TrialEnvironment& environment, const RunSpec& spec, device::HandScript& hand,
             session::Clock clock);
  /// Simulated clock only: runs the loop for `seconds` of loop time (rounded to ticks), the
  /// recorder draining between chunks of ticks as runTrial does; like runTrial, it stops after
  /// the chunk in which a kWindow trial's window ended (the end rule or the maximum).
  void advanceSimulated(double seconds);
  /// Stops the run (the device is commanded zero force) and returns what was recorded
  /// (an empty profile when nothing was), with the run's counters and, as runTrial reports
  /// them (session::noteTrialEnd), its end reason — "pen lifted", "stopped" after
  /// requestStop(), "failed" after a failure (RigStatus::failed; its text in `failure` and the
  /// profile's "failed", nothing after it recorded), else "maximum duration" — and writing span. A mentored run also carries
  /// the mentor's notes, its lost links (mentor_link_faults) and, when the mentor was not
  /// there at the settle's end, the failure (nothing recorded). No-op result when idle.
  session::TrialResult finish();
  /// Ends the trial now (the stop key): the relay disarms the recorder at the next sample it
  /// takes, so nothing after the request is recorded, and finish() reports end_reason
  /// "stopped" (unless the end rule ended it first). The loop keeps running until finish().
  /// Any thread; cleared by start().
  void requestStop() noexcept { stop_.request(); }

  /// kCommand: start / stop taking samples (the start/stop buttons). Any thread.
  void armRecording() noexcept;
  void disarmRecording() noexcept;

  /// The newest sample the loop published (the triple buffer). GUI thread only (the one
  /// reader); false when nothing new since the last call (out keeps the last value).
  bool readLatest(Sample& out) noexcept;
  /// Posts a command to the servo thread's mailbox; false if full or not running.
  bool post(const servo::ServoCommand& command) noexcept;
  /// Switches the guidance mode with its cross-fade, through the mailbox.
  bool switchMode(guidance::TrainingMode mode) noexcept;
  /// Where the reference is now: the point the guidance played at its last tick (with time or
  /// progress indexing alike), or nothing (no reference, a mentored run, before the trial).
  [[nodiscard]] std::optional<Vec3> referenceCue() const noexcept;

  [[nodiscard]] bool active() const noexcept { return run_ != nullptr; }
  [[nodiscard]] RigStatus status() const noexcept;
  [[nodiscard]] const RunSpec& spec() const noexcept { return spec_; }
  /// The loop's live counters (ticks, overruns, faults, drops). Only while active().
  [[nodiscard]] const servo::LiveCounters* counters() const noexcept;
  /// What the servo thread got from the real-time settings (after start in real time).
  [[nodiscard]] std::string realtimeSummary() const;
  [[nodiscard]] session::TrialEnvironment* environment() const noexcept { return environment_; }

 private:
  void pump();           // relay: loop ring → recorder; consumer thread only
  void watchTrial();     // consumer thread only (real time): what ends a trial early
  void takeStop();       // consumer thread only
  void checkMentor();    // consumer thread only: the mentor's link at the settle's end
  void publishStatus();  // consumer thread only

  session::TrialEnvironment* environment_ = nullptr;
  RunSpec spec_;
  session::Clock clock_ = session::Clock::kSimulated;
  std::unique_ptr<session::TrialRun> run_;  // the library's pipeline of this run (its loop, device, guidance)
  std::unique_ptr<session::Recorder> recorder_;
  std::unique_ptr<SpscRing<TickSample>> relay_;
  std::thread relay_thread_;
  std::atomic<bool> relay_stop_{false};
  session::TrialStop stop_;  // requestStop(); the relay takes it

  // Consumer-side state (relay thread or, in simulated time, the caller).
  double window_begin_s_ = 0.0;
  double window_end_s_ = 0.0;
  double period_s_ = 1e-3;
  bool window_armed_ = false;
  bool was_recording_ = false;
  bool stop_taken_ = false;
  std::string mentor_failure_;  // the mentor was unavailable when the settle ended
  std::unique_ptr<session::TrialWatch> watch_;  // real time, kWindow: made once the loop runs
  std::string failure_;                         // what the watch saw end the trial
  std::uint64_t failure_tick_ = std::numeric_limits<std::uint64_t>::max();  // the loop's tick count when seen
  bool mentor_checked_ = false;  // the settle's end was checked

  // Published for the GUI thread.
  std::atomic<bool> status_recording_{false};
  std::atomic<bool> status_window_done_{false};
  std::atomic<bool> status_pen_down_done_{false};
  std::atomic<bool> status_writing_over_{false};
  std::atomic<bool> status_stopped_{false};
  std::atomic<bool> status_failed_{false};
  std::atomic<std::uint64_t> status_recorded_{0};
  std::atomic<double> status_loop_time_s_{0.0};
};

}  // namespace hattr::studio
