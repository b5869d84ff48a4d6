#include "hattr/net/mentor_station.hpp"

#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/passivity.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "hattr/session/trial_physics.hpp"

namespace hattr::net {
namespace {

double rms(double sum_of_squares, std::size_t n) { return n ? std::sqrt(sum_of_squares / static_cast<double>(n)) : 0.0; }

}  // namespace

std::vector<std::string> clampCouplingGains(CouplingGains& gains, Coupling coupling, const session::TrialEnvironment& env) {
  guidance::GuidanceConfig modes;
  modes.position = {.kp_N_per_m = gains.position_kp_N_per_m, .kd_N_s_per_m = gains.position_kd_N_s_per_m};
  modes.force.kp = gains.force_kp;
  modes.force.kd_s = gains.force_kd_s;
  std::vector<std::string> lines;
  for (auto& line : guidance::clampGains(modes, env.limits(), env.rate_hz(), env.impedance())) {
    if ((coupling == Coupling::kPosition && line.starts_with("PCONTROL")) ||
        (coupling == Coupling::kForce && line.starts_with("ALPHA"))) {
      lines.push_back("live " + line);
    }
  }
  gains.position_kp_N_per_m = modes.position.kp_N_per_m;
  gains.position_kd_N_s_per_m = modes.position.kd_N_s_per_m;
  gains.force_kp = modes.force.kp;
  gains.force_kd_s = modes.force.kd_s;
  const auto bilateral = clampImpedance(gains.bilateral_k_N_per_m, gains.bilateral_b_N_s_per_m,
                                        {.stiffness_name = "bilateral K", .damping_name = "bilateral B",
                                         .k_other_N_per_m = env.impedance().tangential_stiffness_N_per_m},
                                        env.limits(), env.rate_hz());
  if (coupling == Coupling::kBilateral) lines.insert(lines.end(), bilateral.begin(), bilateral.end());
  return lines;
}

HeldHand::HeldHand(device::HandScript& script) : script_(script) {
  script_.rewind();
  lifted_ = script_.command(0.0);
  script_.rewind();
  lifted_.pen_down = false;
  lifted_.press_N = 0.0;
  lifted_.v_target_W.setZero();
  lifted_.p_target_W.z() = std::max(lifted_.p_target_W.z(), 0.003);
}

device::HandCommand HeldHand::command(double t_s) noexcept {
  if (rewind_pending_.exchange(false, std::memory_order_acq_rel)) script_.rewind();
  const double start = start_s_.load(std::memory_order_acquire);
  return t_s < start ? lifted_ : script_.command(t_s - start);
}

MentorStation::MentorStation(const StationConfig& config, wire::DatagramLink& link, device::HandScript* hand)
    : config_(config) {
  // The device, opened once (a simulated pen starts above the hand); the world and the coupling's
  // gains clamped to its limits; the coupling, the loop, the recorder.
  environment_ = std::make_unique<session::TrialEnvironment>(config_.device_uri, config_.world, config_.rate_hz);
  device_ = hand ? session::openTrialDevice(config_.device_uri, *hand) : device::openDevice(config_.device_uri, nullptr);
  environment_->bindLimits(device_->limits());
  clamps_ = environment_->worldClamps();
  MentorConfig mentor = config_.mentor;
  mentor.rate_hz = config_.rate_hz;
  const auto gain_clamps = clampCouplingGains(mentor.gains, mentor.coupling, *environment_);
  clamps_.insert(clamps_.end(), gain_clamps.begin(), gain_clamps.end());
  coupling_ = std::make_unique<MentorCoupling>(mentor, link);
  environment_->paper().reset();
  loop_ = std::make_unique<servo::ServoLoop>(*device_, servo::ServoConfig{.rate_hz = config_.rate_hz});
  loop_->setWorld(&environment_->paper());
  loop_->setGuidance(coupling_.get());

  ProfileMetadata metadata = config_.metadata;
  metadata.device = config_.device_uri;
  metadata.created_utc = utcNowIso8601();
  if (metadata.source.empty()) metadata.source = "mentored";
  auto& extra = metadata.extra;
  extra["mentor_role"] = std::string(roleName(mentor.role));
  extra["coupling"] = std::string(couplingName(mentor.coupling));
  extra["passivity"] = mentor.passivity ? "time-domain passivity observer/controller" : "off";
  extra["position_kp_N_per_m"] = fmt::format("{}", mentor.gains.position_kp_N_per_m);
  extra["position_kd_N_s_per_m"] = fmt::format("{}", mentor.gains.position_kd_N_s_per_m);
  extra["force_kp"] = fmt::format("{}", mentor.gains.force_kp);
  extra["force_kd_s"] = fmt::format("{}", mentor.gains.force_kd_s);
  extra["bilateral_k_N_per_m"] = fmt::format("{}", mentor.gains.bilateral_k_N_per_m);
  extra["bilateral_b_N_s_per_m"] = fmt::format("{}", mentor.gains.bilateral_b_N_s_per_m);
  std::string joined;
  for (const auto& c : clamps_) joined += (joined.empty() ? "" : "; ") + c;
  extra["clamps"] = joined.empty() ? "none" : joined;
  recorder_ = std::make_unique<session::Recorder>(
      loop_->samples(), session::RecorderConfig{.nominal_period_s = 1.0 / config_.rate_hz}, metadata);
}

MentorStation::~MentorStation() {
  if (loop_) loop_->stop();
}

HapticProfile MentorStation::takeRecording() {
  recorder_->stop();
  HapticProfile profile = recorder_->takeProfile();
  const MentorStats s = coupling_->stats();
  auto& extra = profile.metadata().extra;
  extra["coupling_energy_in_J"] = fmt::format("{}", s.energy_in_J);
  extra["coupling_energy_out_J"] = fmt::format("{}", s.energy_out_J);
  extra["passivity_dissipated_J"] = fmt::format("{}", s.dissipated_J);
  extra["link_faults"] = fmt::format("{}", s.link_faults);
  extra["peer_packets_received"] = fmt::format("{}", s.peers_received);
  // What the recording did that a good one does not (docs/realtime.md, "Physical events").
  const session::PhysicalEvents events = session::judgeRecording(
      profile, environment_->limits(), loop_->safety().maxForce_N(), environment_->paper().relief(),
      environment_->physicalBounds());
  session::notePhysicalEvents(events, profile.metadata());
  if (events.any()) extra["disturbed"] = session::describePhysicalEvents(events);
  return profile;
}

void MentorStation::newRecording() { recorder_->reset(); }

MentoredRun runMentoredSimulation(const MentoredSetup& setup, device::HandScript& leader_hand,
                                  device::HandScript& follower_hand) {
  HATTR_THROW_UNLESS(std::isfinite(setup.duration_s) && setup.duration_s > 0.0 && setup.duration_s <= 600.0,
                     "mentored run: duration: expected (0, 600] s, got {}", setup.duration_s);
  HATTR_THROW_UNLESS(std::isfinite(setup.settle_s) && setup.settle_s >= 0.3 && setup.settle_s <= 60.0,
                     "mentored run: settle time: expected [0.3, 60] s, got {}", setup.settle_s);
  HATTR_THROW_UNLESS(std::isfinite(setup.round_trip_s) && setup.round_trip_s >= 0.0 && setup.round_trip_s <= 10.0,
                     "mentored run: round trip: expected [0, 10] s, got {}", setup.round_trip_s);

  // The link: half the round trip each way, the same loss, independent draws.
  const LinkConditions there{.delay_s = setup.round_trip_s / 2, .jitter_s = setup.jitter_s, .loss = setup.loss, .seed = setup.seed};
  LinkConditions back = there;
  back.seed = setup.seed * 2654435761u + 1;
  EmulatedLinkPair link(there, back);
  const wire::AuthKey key = wire::randomKey();

  // Two stations; the hands hold the pens lifted while the link comes up.
  session::SettlingHand leader_settling(leader_hand, setup.settle_s);
  session::SettlingHand follower_settling(follower_hand, setup.settle_s);
  const auto station = [&](MentorRole role, const std::string& uri) {
    StationConfig c{.device_uri = uri, .world = setup.world};
    c.mentor = MentorConfig{.role = role, .coupling = setup.coupling, .gains = setup.gains, .passivity = setup.passivity,
                            .key = key, .leader = EmulatedLinkPair::addressOf(0), .deadband = setup.deadband};
    c.metadata.subject = role == MentorRole::kLeader ? "expert" : "trainee";
    return c;
  };
  MentorStation leader(station(MentorRole::kLeader, setup.leader_device), link.end(0), &leader_settling);
  MentorStation follower(station(MentorRole::kFollower, setup.follower_device), link.end(1), &follower_settling);

  // Tick for tick in simulated time; both recorders over the same window.
  const double rate_hz = 1000.0;
  const auto settle_ticks = static_cast<std::size_t>(std::llround(setup.settle_s * rate_hz));
  const auto total_ticks = settle_ticks + static_cast<std::size_t>(std::llround(setup.duration_s * rate_hz));
  for (std::size_t i = 0; i < total_ticks; ++i) {
    if (i == settle_ticks) {
      leader.recorder().start();
      follower.recorder().start();
    }
    leader.loop().runSimulated(1);
    follower.loop().runSimulated(1);
    if (i % 64 == 63) {
      leader.recorder().drain();
      follower.recorder().drain();
    }
  }
  leader.recorder().drain();
  follower.recorder().drain();

  MentoredRun run{.coupling = setup.coupling, .round_trip_s = setup.round_trip_s, .loss = setup.loss, .passivity = setup.passivity};
  run.leader = leader.takeRecording();
  run.follower = follower.takeRecording();

  // The measures: same-time differences, the couplings' energy balance, faults.
  const auto& a = run.leader.samples();
  const auto& b = run.follower.samples();
  const std::size_t n = std::min(a.size(), b.size());
  double position_sq = 0.0, force_sq = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    position_sq += (b[i].p_WT - a[i].p_WT).head<2>().squaredNorm();
    force_sq += (b[i].f_user_W - a[i].f_user_W).squaredNorm();
    run.peak_coupling_force_N = std::max({run.peak_coupling_force_N, a[i].f_guide_W.norm(), b[i].f_guide_W.norm()});
  }
  run.tracking_rms_m = rms(position_sq, n);
  run.force_rms_N = rms(force_sq, n);
  const MentorStats ls = leader.coupling().stats();
  const MentorStats fs = follower.coupling().stats();
  run.energy_generated_J = (ls.energy_out_J - ls.energy_in_J) + (fs.energy_out_J - fs.energy_in_J);
  run.dissipated_J = ls.dissipated_J + fs.dissipated_J;
  run.faults = leader.loop().counters().faults.load() + follower.loop().counters().faults.load();
  run.link_faults = ls.link_faults + fs.link_faults;
  run.leader_stats = ls;
  run.follower_stats = fs;
  run.deadband = setup.deadband;
  run.packets_per_s = 0.5 * static_cast<double>(ls.peers_sent + fs.peers_sent) / (static_cast<double>(total_ticks) / rate_hz);
  return run;
}

}  // namespace hattr::net
