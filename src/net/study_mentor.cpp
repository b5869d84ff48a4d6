#include "hattr/net/study_mentor.hpp"

#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/net/mentor_station.hpp"

namespace hattr::net {
namespace {

/// A margin over the link's handshake and the coupling's fade-in before the trial's clock starts.
constexpr double kSettleMargin_s = 0.1;

std::string number(double value) { return fmt::format("{}", value); }

/// What every mentored trial's metadata says of its coupling: which, the clamps, the energies
/// (TDPA's bookkeeping of this station), the packets.
std::map<std::string, std::string> couplingNotes(Coupling coupling, const MentorConfig& config, const MentorStats& s,
                                                 const std::vector<std::string>& clamps) {
  std::string joined;
  for (const auto& c : clamps) joined += (joined.empty() ? "" : "; ") + c;
  return {{"coupling", std::string(couplingName(coupling))},
          {"passivity", config.passivity ? "time-domain passivity observer/controller" : "off"},
          {"deadband", number(config.deadband)},
          {"coupling_clamps", joined.empty() ? "none" : joined},
          {"coupling_energy_in_J", number(s.energy_in_J)},
          {"coupling_energy_out_J", number(s.energy_out_J)},
          {"passivity_dissipated_J", number(s.dissipated_J)},
          {"peer_packets_received", number(static_cast<double>(s.peers_received))},
          {"peer_packets_sent", number(static_cast<double>(s.peers_sent))},
          {"peer_packets_lost", number(static_cast<double>(s.lost))},
          {"mentor_rtt_ms", number(s.rtt_s * 1e3)}};
}

/// The trainee's coupling for a mentored trial: the study's settings, its mode's coupling, the
/// paper's gains clamped to what the trainee's device renders passively beside the paper.
MentorConfig followerConfig(const session::StudyMentor& spec, guidance::TrainingMode mode,
                            const session::TrialEnvironment& environment, std::vector<std::string>& clamps) {
  MentorConfig config{.role = MentorRole::kFollower, .coupling = couplingOfMode(mode), .passivity = spec.passivity,
                      .deadband = spec.deadband};
  clamps = clampCouplingGains(config.gains, config.coupling, environment);
  return config;
}

// ---- A simulated expert ----------------------------------------------------------------------

/// The trainee's guidance stage: first the expert's station catches up with the trainee's loop
/// time (tick for tick in simulated time), then the trainee's coupling runs. Servo thread.
class LockstepFollower final : public GuidanceController {
 public:
  LockstepFollower(servo::ServoLoop& expert_loop, MentorCoupling& follower, double rate_hz)
      : expert_loop_(expert_loop), follower_(follower), period_s_(1.0 / rate_hz) {}

  Vec3 compute(const PenState& pen, const ContactForces& contact, double dt_s) noexcept override {
    // At most a few catch-up ticks per trainee tick: a real-time trainee loop that fell behind
    // drags the expert along over the next ticks instead of in one long tick.
    constexpr int kMaxCatchUp = 8;
    for (int i = 0; i < kMaxCatchUp && static_cast<double>(expert_ticks_) * period_s_ <= pen.t_s + 0.5 * period_s_; ++i) {
      expert_loop_.runSimulated(1);
      ++expert_ticks_;
    }
    last_t_s_ = pen.t_s;
    return follower_.compute(pen, contact, dt_s);
  }
  [[nodiscard]] double lastTime_s() const noexcept { return last_t_s_; }

 private:
  servo::ServoLoop& expert_loop_;
  MentorCoupling& follower_;
  double period_s_;
  std::uint64_t expert_ticks_ = 0;
  double last_t_s_ = 0.0;
};

class SimulatedStudyMentor final : public session::LiveGuidance {
 public:
  SimulatedStudyMentor(const session::StudyMentor& spec, const HapticProfile& expert, render::WorldConfig world,
                       double rate_hz)
      : spec_(spec), expert_(expert), world_(std::move(world)), rate_hz_(rate_hz) {}

  [[nodiscard]] double minimumSettle_s() const noexcept override {
    return spec_.round_trip_s + spec_.jitter_s + MentorConfig{}.hello_interval_s + MentorConfig{}.ramp_s + kSettleMargin_s;
  }

  GuidanceController& beginTrial(guidance::TrainingMode mode, const session::TrialEnvironment& environment,
                                 double settle_s, std::uint64_t seed) override {
    endSession();
    // The link: half the round trip each way, the same loss, independent draws per direction.
    const LinkConditions there{.delay_s = spec_.round_trip_s / 2, .jitter_s = spec_.jitter_s, .loss = spec_.loss, .seed = seed};
    LinkConditions back = there;
    back.seed = seed * 2654435761u + 1;
    link_.emplace(there, back);
    const wire::AuthKey key = wire::randomKey();

    // The expert's station: their pen and paper, their hand writing the reference after the
    // same settle time as the trainee's, so both start writing together.
    follower_config_ = followerConfig(spec_, mode, environment, clamps_);
    follower_config_.key = key;
    follower_config_.leader = EmulatedLinkPair::addressOf(0);
    expert_script_.emplace(expert_);
    expert_hand_.emplace(*expert_script_, settle_s);
    StationConfig station{.device_uri = spec_.expert_device, .world = world_, .rate_hz = rate_hz_};
    station.mentor = MentorConfig{.role = MentorRole::kLeader, .coupling = follower_config_.coupling,
                                  .passivity = spec_.passivity, .key = key, .deadband = spec_.deadband};
    station.metadata.subject = "expert";
    expert_station_ = std::make_unique<MentorStation>(station, link_->end(0), &*expert_hand_);

    // The trainee's side.
    follower_ = std::make_unique<MentorCoupling>(follower_config_, link_->end(1));
    stage_.emplace(expert_station_->loop(), *follower_, rate_hz_);
    return *stage_;
  }

  [[nodiscard]] std::string unavailable() const override {
    if (follower_ && follower_->stats().link_up) return "";
    return fmt::format("the simulated expert's link did not come up during the settle phase (round trip {} ms, "
                       "loss {} %)", spec_.round_trip_s * 1e3, spec_.loss * 100.0);
  }

  std::map<std::string, std::string> endTrial(session::TrialResult& result) override {
    HATTR_DEMAND(follower_ != nullptr, "endTrial() without beginTrial()");
    follower_->close(units::secondsToNanoseconds(stage_->lastTime_s()));
    const MentorStats s = follower_->stats();
    // The trainee's side ends each trial's session; a goodbye heard means the expert left mid-trial.
    result.mentor_link_faults += s.link_faults + s.goodbyes_received;
    auto notes = couplingNotes(follower_config_.coupling, follower_config_, s, clamps_);
    notes["mentor"] = fmt::format("simulated expert on {}", spec_.expert_device);
    notes["mentor_link"] = fmt::format("emulated: round trip {} ms, jitter {} ms, loss {} %", spec_.round_trip_s * 1e3,
                                       spec_.jitter_s * 1e3, spec_.loss * 100.0);
    const MentorStats expert = expert_station_->coupling().stats();
    notes["expert_coupling_energy_in_J"] = number(expert.energy_in_J);
    notes["expert_coupling_energy_out_J"] = number(expert.energy_out_J);
    endSession();
    return notes;
  }

 private:
  void endSession() {
    stage_.reset();
    follower_.reset();
    expert_station_.reset();
    expert_hand_.reset();
    expert_script_.reset();
    link_.reset();
  }

  session::StudyMentor spec_;
  HapticProfile expert_;
  render::WorldConfig world_;
  double rate_hz_;
  // One trial's parts, in the order they depend on each other.
  std::optional<EmulatedLinkPair> link_;
  std::optional<device::ProfileHandScript> expert_script_;
  std::optional<session::SettlingHand> expert_hand_;
  std::unique_ptr<MentorStation> expert_station_;
  MentorConfig follower_config_;
  std::vector<std::string> clamps_;
  std::unique_ptr<MentorCoupling> follower_;
  std::optional<LockstepFollower> stage_;
};

// ---- A live expert -----------------------------------------------------------------------------

class LiveStudyMentor final : public session::LiveGuidance {
 public:
  explicit LiveStudyMentor(const session::StudyMentor& spec)
      : spec_(spec),
        leader_(wire::parseUdpEndpoint(spec.connect, "mentor.connect")),
        key_(wire::readKeyFile(spec.key)) {}

  /// The handshake (HELLO every 50 ms until welcomed) and the fade-in, with room for a slow link.
  [[nodiscard]] double minimumSettle_s() const noexcept override { return 1.0; }

  GuidanceController& beginTrial(guidance::TrainingMode mode, const session::TrialEnvironment& environment,
                                 double /*settle_s*/, std::uint64_t /*seed*/) override {
    follower_.reset();
    config_ = followerConfig(spec_, mode, environment, clamps_);
    config_.key = key_;
    config_.leader = leader_;
    link_ = std::make_unique<wire::UdpDatagramLink>(wire::UdpSocket::connected(leader_), wire::UdpDatagramLink::Clock::kLoop);
    follower_ = std::make_unique<MentorCoupling>(config_, *link_);
    return *follower_;
  }

  [[nodiscard]] std::string unavailable() const override {
    const MentorStats s = follower_ ? follower_->stats() : MentorStats{};
    if (s.link_up) return "";
    if (s.refused_busy) return fmt::format("the expert's station at {} mentors another trainee", spec_.connect);
    return fmt::format("no answer from the expert's station at {} (is `hattr mentor lead --sessions 0` running there "
                       "with the same key? a wrong key looks like this too: its packets are dropped unanswered)",
                       spec_.connect);
  }

  std::map<std::string, std::string> endTrial(session::TrialResult& result) override {
    HATTR_DEMAND(follower_ != nullptr, "endTrial() without beginTrial()");
    follower_->close(0);  // BYE: the expert's station ends this session and waits for the next
    const MentorStats s = follower_->stats();
    // The trainee's side ends each trial's session; a goodbye heard means the expert left mid-trial.
    result.mentor_link_faults += s.link_faults + s.goodbyes_received;
    auto notes = couplingNotes(config_.coupling, config_, s, clamps_);
    notes["mentor"] = fmt::format("live expert at {}", spec_.connect);
    follower_.reset();
    link_.reset();
    return notes;
  }

 private:
  session::StudyMentor spec_;
  wire::UdpEndpoint leader_;
  wire::AuthKey key_;
  MentorConfig config_;
  std::vector<std::string> clamps_;
  std::unique_ptr<wire::UdpDatagramLink> link_;
  std::unique_ptr<MentorCoupling> follower_;
};

}  // namespace

Coupling couplingOfMode(guidance::TrainingMode mode) {
  HATTR_THROW_UNLESS(guidance::isMentored(mode), "mode {}: not a mentored mode", guidance::modeName(mode));
  return static_cast<Coupling>(static_cast<int>(mode) - static_cast<int>(guidance::TrainingMode::kMentorObserve));
}

std::unique_ptr<session::LiveGuidance> makeStudyMentor(const session::StudyMentor& mentor, const HapticProfile& expert,
                                                       const render::WorldConfig& world, double rate_hz) {
  if (mentor.expert == "live") return std::make_unique<LiveStudyMentor>(mentor);
  HATTR_THROW_UNLESS(mentor.expert == "simulated", "mentor.expert: expected \"simulated\" or \"live\", got \"{}\"",
                     mentor.expert);
  return std::make_unique<SimulatedStudyMentor>(mentor, expert, world, rate_hz);
}

}  // namespace hattr::net
