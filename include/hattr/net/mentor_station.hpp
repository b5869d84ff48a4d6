#pragma once
/// A mentoring station: one person's device (by URI; a simulated pen is held by a hand
/// script), their paper, the coupling to the other station, the servo loop with its safety
/// path, and a recorder, so both sides of a mentored session are haptic profiles the paper's
/// metrics apply to. Also the two-station simulation that measures the couplings under delay
/// and loss, in simulated time (docs/mentoring.md).
///
/// Threads: setup and the run functions are main-thread code; the loop runs the coupling.

#include <algorithm>
#include <memory>
#include <string>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/net/mentor.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/servo/servo_loop.hpp"
#include "hattr/session/recorder.hpp"
#include "hattr/session/trial.hpp"

namespace hattr::net {

/// A simulated hand for a live session: holds the pen lifted above the script's first point
/// until release(), then plays the script from that loop time, so two stations' hands start
/// together once their link is up. release() from any thread; command() on the servo thread.
class HeldHand final : public device::HandScript {
 public:
  explicit HeldHand(device::HandScript& script);
  device::HandCommand command(double t_s) noexcept override;
  void rewind() noexcept override { script_.rewind(); }
  /// The script starts at loop time `t_s`.
  void release(double t_s) noexcept { start_s_.store(t_s, std::memory_order_release); }
  /// Lifted again, the script back at its start, until the next release() (a new session).
  void hold() noexcept {
    start_s_.store(std::numeric_limits<double>::infinity(), std::memory_order_release);
    rewind_pending_.store(true, std::memory_order_release);
  }

 private:
  device::HandScript& script_;
  device::HandCommand lifted_;
  std::atomic<double> start_s_{std::numeric_limits<double>::infinity()};
  std::atomic<bool> rewind_pending_{false};  // the servo thread rewinds the script
};

/// The simulated trainee of the mentoring tests and table (docs/mentoring.md): plays the
/// expert's plan `lag_s` late and `offset_W` off it. Servo thread: noexcept, no allocation.
class LaggingHand final : public device::HandScript {
 public:
  LaggingHand(const HapticProfile& plan, double lag_s = 0.15, Vec3 offset_W = Vec3(0.003, -0.002, 0.0))
      : plan_(plan), lag_s_(lag_s), offset_W_(offset_W) {}
  device::HandCommand command(double t_s) noexcept override {
    device::HandCommand c = plan_.command(std::max(0.0, t_s - lag_s_));
    c.p_target_W += offset_W_;
    return c;
  }
  void rewind() noexcept override { plan_.rewind(); }

 private:
  device::ProfileHandScript plan_;
  double lag_s_;
  Vec3 offset_W_;
};

/// The coupling's gains clamped to what `environment`'s device renders passively beside the
/// paper: live PCONTROL and ALPHA as the training modes are clamped, the bilateral spring in
/// the plane beside the friction spring. Returns the lines of what changed for `coupling`.
std::vector<std::string> clampCouplingGains(CouplingGains& gains, Coupling coupling,
                                            const session::TrialEnvironment& environment);

struct StationConfig {
  std::string device_uri = "sim://pen";
  render::WorldConfig world{};
  double rate_hz = 1000.0;
  MentorConfig mentor;
  ProfileMetadata metadata;   ///< subject, skill, ...; role, coupling, gains are added
};

class MentorStation {
 public:
  /// Opens the device (a simulated pen held by `hand`, which may be null and must outlive the
  /// station), builds the paper, clamps the coupling's gains to what the device renders
  /// passively beside the paper (as the training modes are), and the loop. Throws InputError.
  MentorStation(const StationConfig& config, wire::DatagramLink& link, device::HandScript* hand);
  ~MentorStation();
  MentorStation(const MentorStation&) = delete;
  MentorStation& operator=(const MentorStation&) = delete;

  [[nodiscard]] servo::ServoLoop& loop() noexcept { return *loop_; }
  [[nodiscard]] MentorCoupling& coupling() noexcept { return *coupling_; }
  [[nodiscard]] session::Recorder& recorder() noexcept { return *recorder_; }
  [[nodiscard]] device::Device& device() noexcept { return *device_; }
  /// Every gain clamped for this device ("position Kd 170 N·s/m -> 0.46 N·s/m: ...").
  [[nodiscard]] const std::vector<std::string>& clamps() const noexcept { return clamps_; }
  /// The recording so far, with the coupling's totals and its physical events (session::
  /// judgeRecording; `disturbed` when any) in its metadata; stops recording.
  /// After the recorder's thread stopped (or before it started).
  [[nodiscard]] HapticProfile takeRecording();
  /// Between sessions, the recorder's thread stopped: the next recording starts from nothing.
  void newRecording();

 private:
  StationConfig config_;
  std::unique_ptr<session::TrialEnvironment> environment_;
  std::unique_ptr<device::Device> device_;
  std::unique_ptr<MentorCoupling> coupling_;
  std::unique_ptr<servo::ServoLoop> loop_;
  std::unique_ptr<session::Recorder> recorder_;
  std::vector<std::string> clamps_;
};

/// One row of the mentoring table: a coupling under a round trip and a loss rate.
struct MentoredRun {
  Coupling coupling = Coupling::kObserve;
  double round_trip_s = 0.0;
  double loss = 0.0;
  bool passivity = true;
  HapticProfile leader;              ///< both sides, recorded over the same loop-time window
  HapticProfile follower;
  double tracking_rms_m = 0.0;       ///< follower's pen vs the leader's, in the paper plane, same time
  double force_rms_N = 0.0;          ///< follower's force on the paper vs the leader's
  double energy_generated_J = 0.0;   ///< what the couplings gave both people less what they took in
  double dissipated_J = 0.0;         ///< what the passivity controllers took out
  std::uint64_t faults = 0;          ///< latched faults on either side
  std::uint64_t link_faults = 0;
  double peak_coupling_force_N = 0.0;
  double deadband = 0.0;             ///< the deadband's Weber fraction (0: a PEER every tick)
  double packets_per_s = 0.0;        ///< PEERs sent per second and direction, mean of the two, whole run
  MentorStats leader_stats;          ///< each coupling's counters at the end
  MentorStats follower_stats;
};

struct MentoredSetup {
  Coupling coupling = Coupling::kObserve;
  CouplingGains gains;
  bool passivity = true;
  double round_trip_s = 0.0;   ///< split evenly between the two directions
  double jitter_s = 0.0;
  double loss = 0.0;
  double deadband = 0.0;       ///< MentorConfig::deadband of both stations
  std::uint64_t seed = 1;
  double duration_s = 3.0;     ///< recorded after the settle time
  double settle_s = 0.5;       ///< both pens held lifted while the link comes up and forces ramp in
  std::string leader_device = "sim://pen";
  std::string follower_device = "sim://pen";
  render::WorldConfig world{};
};

/// Two stations in one process on an emulated link, in simulated time (deterministic for a
/// seed): the leader's hand writes, the follower's hand does what it does; both are recorded
/// over [settle_s, settle_s + duration_s). Throws InputError for bad settings.
MentoredRun runMentoredSimulation(const MentoredSetup& setup, device::HandScript& leader_hand,
                                  device::HandScript& follower_hand);

}  // namespace hattr::net
