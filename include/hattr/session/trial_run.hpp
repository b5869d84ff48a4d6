#pragma once
/// One trial's pipeline, built as runTrial builds it and kept open while it runs: the set-up
/// checked, the guidance with its gains clamped to what the paper and device render passively
/// (or a mentored mode's live stage), the hand settling above the paper, the device, the paper
/// reset, the servo loop, the recorder's configuration and the recording's metadata; and, once
/// the loop has stopped, the trial's result. runTrial drives one to its end in a single call;
/// the studio's live rig drives one from its window, showing the pen while it runs. Either way
/// the trial is built and reported by the same code.
///
/// Built, finished and destroyed on one thread; while it runs, the loop it owns runs on its own
/// thread in real time, and device(), live() and mentorUnavailable() may be read from another
/// (the studio's relay thread).

#include <memory>
#include <string>
#include <vector>

#include "hattr/servo/servo_loop.hpp"
#include "hattr/session/recorder.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::session {

/// Ticks a simulated-time trial runs between drains of the loop's sample ring (runTrial and the
/// studio's rig alike, so the end rule stops both loops after the same chunk).
inline constexpr std::size_t kSimulatedChunk = 64;

class TrialRun {
 public:
  /// Builds the trial. Throws InputError for a bad duration, end rule or settle time, a
  /// mentored mode without its expert's station, or a bad device URI. `follow_during_settle`:
  /// the lifted pen follows a live hand while settling (a person moves to the start) instead
  /// of being held above the script's first point. `environment`, `hand`, the setup's reference
  /// and live guidance must outlive the run.
  TrialRun(TrialEnvironment& environment, const TrialSetup& setup, device::HandScript& hand,
           bool follow_during_settle = false);
  ~TrialRun();
  TrialRun(const TrialRun&) = delete;
  TrialRun& operator=(const TrialRun&) = delete;

  [[nodiscard]] servo::ServoLoop& loop() noexcept { return *loop_; }
  [[nodiscard]] const device::Device& device() const noexcept { return *device_; }
  /// The stage the loop runs when the mode is not mentored (its reference cue is the marker's).
  [[nodiscard]] const guidance::TrainingGuidance& guidance() const noexcept { return *guidance_; }
  /// The clock that runs the trial: the set-up's, or real time for a device that cannot be simulated.
  [[nodiscard]] Clock clock() const noexcept { return clock_; }
  /// The settle phase [s]: the set-up's, lengthened to a mentor's minimum.
  [[nodiscard]] double settle_s() const noexcept { return settle_s_; }
  /// Every gain and world clamp applied.
  [[nodiscard]] const std::vector<std::string>& clamps() const noexcept { return clamps_; }
  /// A mentored mode's live guidance, or null.
  [[nodiscard]] LiveGuidance* live() const noexcept { return live_; }
  /// The recorder's configuration: the set-up's trigger, the servo period and the end rule
  /// (the pen-up stop follows the end rule when there is one). The recording window is the driver's.
  [[nodiscard]] const RecorderConfig& recorderConfig() const noexcept { return recorder_config_; }
  /// The recording's metadata (trialMetadata, and "clock: device" for a device's own clock).
  [[nodiscard]] const ProfileMetadata& metadata() const noexcept { return metadata_; }
  /// At the settle's end: why a mentored trial's expert is not there; "" when there (or none).
  [[nodiscard]] std::string mentorUnavailable() const;

  /// After the loop and the recorder stopped: the trial's result. The loop's counters and the
  /// recorder's missed samples; a mentor's session ended and its notes; the end reason and the
  /// writing span (noteTrialEnd; "failed" when `failure` is not empty, "stopped" when
  /// `stopped`); the failure and any lost device links noted in the metadata; the recording
  /// judged against the set-up's bounds (TrialResult::physics) and, with every counter, noted in
  /// its metadata (noteLoopCounters). Call once.
  TrialResult finish(Recorder& recorder, std::string failure, bool stopped);

 private:
  /// Opens the trial's device (with the settling hand), binds its limits to the environment and
  /// runs the setup's check of them.
  void openDevice(TrialEnvironment& environment, const TrialSetup& setup);

  std::vector<std::string> clamps_;
  std::unique_ptr<guidance::TrainingGuidance> guidance_;
  LiveGuidance* live_ = nullptr;
  double settle_s_ = 0.0;
  std::unique_ptr<SettlingHand> settling_;
  std::unique_ptr<device::Device> device_;
  Clock clock_ = Clock::kSimulated;
  std::unique_ptr<servo::ServoLoop> loop_;
  ProfileMetadata metadata_;
  RecorderConfig recorder_config_;
  TrialEnvironment* environment_;
  PhysicalBounds bounds_;
};

}  // namespace hattr::session
