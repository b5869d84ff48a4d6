#include "core/mentor_session.hpp"

#include <fmt/format.h>

#include <cmath>

#include "hattr/core/error.hpp"

namespace hattr::studio {
namespace {

/// The pen is held lifted (following the hand) this long while the loop's forces ramp in, as in
/// the live rig's free writing: a pen pressed down from the first tick would sink into a paper
/// whose force is still ramping in.
constexpr double kSettle_s = 0.3;
static_assert(kSettle_s >= servo::SafetyConfig{}.ramp_time_s);

bool isLeader(const MentorSettings& settings) { return settings.role == net::MentorRole::kLeader; }

}  // namespace

MentorSetup mentorSetupFor(const MentorSettings& settings) {
  HATTR_THROW_UNLESS(std::isfinite(settings.wait_s) && settings.wait_s >= 0.1 && settings.wait_s <= 3600.0,
                     "wait for the other station: expected [0.1, 3600] s, got {}", settings.wait_s);
  MentorSetup setup;
  net::MentorConfig& mentor = setup.mentor;
  mentor.role = settings.role;
  mentor.coupling = settings.coupling;
  mentor.passivity = settings.passivity;
  mentor.deadband = settings.deadband;
  // The address, then the key: the library's own messages.
  if (isLeader(settings)) {
    setup.bind = wire::parseUdpEndpoint(settings.address, "listen address", 0);
  } else {
    mentor.leader = wire::parseUdpEndpoint(settings.address, "leader's address");
  }
  HATTR_THROW_UNLESS(!settings.key_file.empty(),
                     "key file: none chosen; make one with `hattr device keygen --out FILE` and use the same file on "
                     "both stations");
  mentor.key = wire::readKeyFile(settings.key_file);
  mentor.validate();
  return setup;
}

std::string mentorPhaseText(const MentorSnapshot& snapshot) {
  switch (snapshot.phase) {
    case MentorPhase::kIdle: return "not connected";
    case MentorPhase::kWaiting: return snapshot.where + " …";
    case MentorPhase::kLinked:
      if (snapshot.link_down_now) {
        return fmt::format("link down for {:.0f} ms: no coupling force", snapshot.link_down_s * 1e3);
      }
      return "linked";
    case MentorPhase::kEnded:
      if (!snapshot.failure.empty()) return snapshot.failure;
      return snapshot.ended_by_other ? "the other station ended the session" : "session over (stopped)";
  }
  return {};
}

MentorSession::MentorSession() = default;

MentorSession::~MentorSession() { stop(); }

void MentorSession::start(const MentorSettings& settings, device::HandScript& hand) {
  stop();
  // Everything that can be refused is checked before anything runs.
  const MentorSetup setup = mentorSetupFor(settings);
  net::LinkWatch watch({.wait_s = settings.wait_s, .give_up_s = settings.give_up_s,
                        .leader_address = settings.address},
                       setup.mentor, Clock::now());
  // A follower's socket is connected to its leader: the kernel delivers only the leader's datagrams.
  auto link = std::make_unique<wire::UdpDatagramLink>(isLeader(settings) ? wire::UdpSocket::bound(setup.bind)
                                                                         : wire::UdpSocket::connected(setup.mentor.leader),
                                                      wire::UdpDatagramLink::Clock::kLoop);
  net::StationConfig config{.device_uri = settings.device_uri, .world = settings.world, .rate_hz = settings.rate_hz,
                            .mentor = setup.mentor};
  config.metadata.subject = !settings.subject.empty() ? settings.subject : isLeader(settings) ? "expert" : "trainee";
  auto settling = std::make_unique<session::SettlingHand>(hand, kSettle_s, true);
  auto station = std::make_unique<net::MentorStation>(config, *link, settling.get());

  // The loop in real time, its samples drained by the recorder's thread (recording starts once linked).
  station->loop().requireConsumer(&station->recorder().consumerTime());
  station->recorder().startThread();
  try {
    station->loop().start();
  } catch (...) {
    station->recorder().stopThread();
    throw;
  }

  settings_ = settings;
  where_ = isLeader(settings) ? "listening on " + link->localEndpoint().text()
                              : "connecting to " + setup.mentor.leader.text();
  clamps_ = station->clamps();
  link_ = std::move(link);
  settling_ = std::move(settling);
  station_ = std::move(station);
  phase_ = MentorPhase::kWaiting;
  failure_.clear();
  ended_by_other_ = false;
  last_stats_ = {};
  final_counters_ = {};
  watch.restart(Clock::now(), {});  // the wait begins now that everything runs, on a new station
  watch_ = std::move(watch);
  own_.reset();
  own_fresh_ = false;
  peer_ = {};
  peer_trail_.clear();
  recording_.reset();
  recording_saved_ = true;
}

bool MentorSession::poll() {
  own_fresh_ = false;
  if (!station_) return false;
  // This station's pen and the other's.
  Sample sample;
  if (station_->loop().latest().read(sample)) {
    own_ = sample;
    own_fresh_ = true;
  }
  net::PeerView view;
  if (station_->coupling().peer().read(view) && view.valid) {
    peer_ = view;
    Sample point;
    point.t_s = view.t_s;
    point.p_WT = view.p_WT;
    point.pen_down = view.pen_down;
    point.in_contact = view.pen_down;
    peer_trail_.append(point);
  }
  last_stats_ = station_->coupling().stats();
  watchLink(last_stats_, Clock::now());
  return station_ == nullptr;
}

// The watch (net::LinkWatch, as `hattr mentor`): linked, refused, nobody in time, a goodbye or
// a lost link; a stopped loop ends the session too.
void MentorSession::watchLink(const net::MentorStats& stats, Clock::time_point now) {
  if (!station_->loop().running()) {
    end("the servo loop stopped");
    return;
  }
  if (watch_->observe(stats, now)) {
    phase_ = MentorPhase::kLinked;
    station_->recorder().start();
  }
  if (watch_->phase() == net::LinkPhase::kEnded) end(watch_->failure(), watch_->endedByOther());
}

void MentorSession::stop() { end({}); }

// Stops the loop and the recorder, says BYE, keeps the recording (marked failed on a failure).
void MentorSession::end(const std::string& failure, bool by_other) {
  if (!station_) return;
  net::MentorStation& station = *station_;
  station.loop().stop();
  station.recorder().stopThread();
  Sample last = own_.value_or(Sample{});
  (void)station.loop().latest().read(last);
  station.coupling().close(static_cast<std::int64_t>(last.t_s * 1e9));
  last_stats_ = station.coupling().stats();
  copyCounters(final_counters_);
  HapticProfile recorded = station.takeRecording();
  station_.reset();
  settling_.reset();
  link_.reset();

  phase_ = MentorPhase::kEnded;
  failure_ = failure;
  ended_by_other_ = by_other;
  if (!recorded.empty()) {
    if (!failure.empty()) recorded.metadata().extra["failed"] = failure;
    recording_ = std::move(recorded);
    recording_saved_ = false;
  }
}

void MentorSession::copyCounters(MentorSnapshot& out) const {
  if (!station_) {
    out.ticks = final_counters_.ticks;
    out.overruns = final_counters_.overruns;
    out.faults = final_counters_.faults;
    out.stalls = final_counters_.stalls;
    return;
  }
  const servo::LiveCounters& c = station_->loop().counters();
  out.ticks = c.ticks.load();
  out.overruns = c.overruns.load();
  out.faults = c.faults.load();
  out.stalls = c.stalls.load() + c.consumer_stalls.load();
}

MentorSnapshot MentorSession::snapshot() const {
  MentorSnapshot s;
  s.phase = phase_;
  s.role = settings_.role;
  s.where = where_;
  s.failure = failure_;
  s.ended_by_other = ended_by_other_;
  s.stats = last_stats_;
  copyCounters(s);
  const auto now = Clock::now();
  if (phase_ == MentorPhase::kLinked) {
    s.linked_s = watch_->linkedFor_s(now);
    s.link_down_now = watch_->linkDown();
    s.link_down_s = watch_->downFor_s(now);
  }
  return s;
}

wire::UdpEndpoint MentorSession::localEndpoint() const {
  HATTR_DEMAND(link_ != nullptr, "localEndpoint() needs a running session");
  return link_->localEndpoint();
}

const servo::LiveCounters* MentorSession::counters() const noexcept {
  return station_ ? &station_->loop().counters() : nullptr;
}

SaveOutcome MentorSession::saveRecording(const std::filesystem::path& file, bool replace_confirmed) {
  HATTR_THROW_UNLESS(recording_.has_value(), "{}: nothing to save: the last session recorded nothing", file.string());
  const SaveOutcome outcome = saveProfile(*recording_, file, replace_confirmed);
  if (outcome == SaveOutcome::kSaved) recording_saved_ = true;
  return outcome;
}

void MentorSession::discardRecording() {
  recording_.reset();
  recording_saved_ = true;
}

}  // namespace hattr::studio
