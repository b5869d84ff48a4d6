#include "hattr/ops/mentor_station_run.hpp"

#include <cmath>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/wire/keys.hpp"

namespace hattr::ops {
namespace {

/// A person's hand drives the pen from the start, held lifted (following the hand) this long
/// while the loop's forces ramp in: a pen pressed down from the first tick would sink into a
/// paper whose force is still ramping in (as the live rig's free writing does).
constexpr double kSettle_s = 0.3;
static_assert(kSettle_s >= servo::SafetyConfig{}.ramp_time_s);

bool isLeader(const MentorStationOptions& options) { return options.role == net::MentorRole::kLeader; }

}  // namespace

MentorSetup mentorSetupFor(const MentorStationOptions& options) {
  HATTR_THROW_UNLESS(std::isfinite(options.wait_s) && (options.wait_s < 0.0 || (options.wait_s >= 0.1 && options.wait_s <= 3600.0)),
                     "wait for the other station: expected [0.1, 3600] s (or below 0: without limit), got {}",
                     options.wait_s);
  MentorSetup setup;
  net::MentorConfig& mentor = setup.mentor;
  mentor.role = options.role;
  mentor.coupling = options.coupling;
  mentor.passivity = options.passivity;
  mentor.deadband = options.deadband;
  // The address, then the key: the library's own messages.
  if (isLeader(options)) {
    setup.bind = wire::parseUdpEndpoint(options.address, options.listen_what, 0);
  } else {
    mentor.leader = wire::parseUdpEndpoint(options.address, options.connect_what);
  }
  HATTR_THROW_UNLESS(!options.key_file.empty(),
                     "{}: none chosen; make one with `hattr device keygen --out FILE` and use the same file on both "
                     "stations", options.key_what);
  mentor.key = wire::readKeyFile(options.key_file);
  mentor.validate();
  return setup;
}

nlohmann::json MentorSessionOutcome::toJson() const {
  const net::MentorStats& s = stats;
  return {{"samples", recording.size()},
          {"peers_received", s.peers_received},
          {"peers_sent", s.peers_sent},
          {"peers_withheld", s.peers_withheld},
          {"lost", s.lost},
          {"link_faults", s.link_faults},
          {"busy_refusals", s.busy_refusals},
          {"drops", dropsJson(s.drops)},
          {"energy_in_J", s.energy_in_J},
          {"energy_out_J", s.energy_out_J},
          {"dissipated_J", s.dissipated_J},
          {"rtt_ms", s.rtt_s * 1e3},
          {"failure", failure}};
}

MentorStationRun::MentorStationRun(const MentorStationOptions& options, device::HandScript* hand, HandStart start)
    : setup_(mentorSetupFor(options)),
      watch_({.wait_s = options.wait_s, .give_up_s = options.give_up_s, .leader_address = options.address},
             setup_.mentor, Clock::now()) {
  // A follower's socket is connected to its leader: the kernel delivers only the leader's datagrams.
  link_ = std::make_unique<wire::UdpDatagramLink>(isLeader(options) ? wire::UdpSocket::bound(setup_.bind)
                                                                    : wire::UdpSocket::connected(setup_.mentor.leader),
                                                  wire::UdpDatagramLink::Clock::kLoop);
  device::HandScript* driving = hand;
  if (hand != nullptr && start == HandStart::kHeldUntilLinked) {
    held_ = std::make_unique<net::HeldHand>(*hand);
    driving = held_.get();
  } else if (hand != nullptr) {
    settling_ = std::make_unique<session::SettlingHand>(*hand, kSettle_s, true);
    driving = settling_.get();
  }
  net::StationConfig config{.device_uri = options.device_uri, .world = options.world, .rate_hz = options.rate_hz,
                            .mentor = setup_.mentor};
  config.metadata.subject = !options.subject.empty() ? options.subject : isLeader(options) ? "expert" : "trainee";
  station_ = std::make_unique<net::MentorStation>(config, *link_, driving);

  // The loop in real time, its samples drained by the recorder's thread (recording starts once linked).
  station_->loop().requireConsumer(&station_->recorder().consumerTime());
  station_->recorder().startThread();
  try {
    station_->loop().start();
  } catch (...) {
    station_->recorder().stopThread();
    throw;
  }
  where_ = isLeader(options) ? "listening on " + link_->localEndpoint().text()
                             : "connecting to " + setup_.mentor.leader.text();
  watch_.restart(Clock::now(), station_->coupling().stats());  // the wait begins now that everything runs
}

MentorStationRun::~MentorStationRun() { close(); }

double MentorStationRun::loopTime() {
  Sample s;
  (void)station_->loop().latest().read(s);
  return s.t_s;
}

bool MentorStationRun::poll(Clock::time_point now) {
  if (closed_ || ended()) return false;
  if (!station_->loop().running()) {  // a stopped loop ends the session
    loop_stopped_ = true;
    watch_.end();
    return false;
  }
  if (!watch_.observe(station_->coupling().stats(), now)) return false;
  // Linked: both sides record; a held hand starts once the coupling has faded in.
  if (held_) held_->release(loopTime() + setup_.mentor.ramp_s);
  station_->recorder().start();
  return true;
}

void MentorStationRun::endNow() { watch_.end(); }

MentorSessionOutcome MentorStationRun::takeSession() {
  // Everything the loop published before now is the session's, however far behind the
  // recorder's thread is (the loop runs on for the next session).
  station_->recorder().stopBefore(station_->loop().counters().ticks.load(std::memory_order_acquire));
  station_->recorder().stopThread();
  MentorSessionOutcome out;
  out.recording = station_->takeRecording();
  const net::MentorStats after = station_->coupling().stats();
  out.stats = net::statsSince(after, before_session_);
  before_session_ = after;
  out.failure = failure();
  out.ended_by_other = watch_.endedByOther();
  if (!out.failure.empty() && !out.recording.empty()) out.recording.metadata().extra["failed"] = out.failure;
  return out;
}

void MentorStationRun::nextSession(Clock::time_point now) {
  HATTR_DEMAND(!closed_ && !loop_stopped_, "nextSession() on a station whose loop has stopped");
  // Ready for the next follower: the hand lifted and rewound, a fresh recording (the recorder's
  // thread stopped first, whether or not takeSession() stopped it).
  station_->recorder().stopThread();
  if (held_) held_->hold();
  station_->newRecording();
  station_->recorder().startThread();
  watch_.restart(now, station_->coupling().stats());
}

void MentorStationRun::close() {
  if (closed_) return;
  closed_ = true;
  station_->loop().stop();
  station_->recorder().stopThread();
  station_->coupling().close(units::secondsToNanoseconds(loopTime()));
}

}  // namespace hattr::ops
