#include "core/mentor_session.hpp"

#include <fmt/format.h>

#include <cmath>

#include "hattr/core/error.hpp"

namespace hattr::studio {

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
  // Everything that can be refused is checked before anything runs; the hand is held lifted,
  // following the person's, while the loop's forces ramp in.
  auto run = std::make_unique<ops::MentorStationRun>(settings, &hand, ops::MentorStationRun::HandStart::kFromTheStart);
  settings_ = settings;
  where_ = run->where();
  clamps_ = run->station().clamps();
  run_ = std::move(run);
  phase_ = MentorPhase::kWaiting;
  failure_.clear();
  ended_by_other_ = false;
  last_stats_ = {};
  final_counters_ = {};
  own_.reset();
  own_fresh_ = false;
  peer_ = {};
  peer_trail_.clear();
  recording_.reset();
  recording_saved_ = true;
}

bool MentorSession::poll() {
  own_fresh_ = false;
  if (!run_) return false;
  net::MentorStation& station = run_->station();
  // This station's pen and the other's.
  Sample sample;
  if (station.loop().latest().read(sample)) {
    own_ = sample;
    own_fresh_ = true;
  }
  net::PeerView view;
  if (station.coupling().peer().read(view) && view.valid) {
    peer_ = view;
    Sample point;
    point.t_s = view.t_s;
    point.p_WT = view.p_WT;
    point.pen_down = view.pen_down;
    point.in_contact = view.pen_down;
    peer_trail_.append(point);
  }
  last_stats_ = station.coupling().stats();
  // The watch: linked, refused, nobody in time, a goodbye, a lost link or a stopped loop.
  if (run_->poll(Clock::now())) phase_ = MentorPhase::kLinked;
  if (run_->ended()) end();
  return run_ == nullptr;
}

void MentorSession::stop() { end(); }

// Ends the session (a normal end unless it had ended), keeps the recording (marked failed on a
// failure), stops the loop and says BYE.
void MentorSession::end() {
  if (!run_) return;
  run_->endNow();
  ops::MentorSessionOutcome outcome = run_->takeSession();
  run_->close();
  last_stats_ = run_->station().coupling().stats();
  copyCounters(final_counters_);
  run_.reset();

  phase_ = MentorPhase::kEnded;
  failure_ = outcome.failure;
  ended_by_other_ = outcome.ended_by_other;
  if (!outcome.recording.empty()) {
    recording_ = std::move(outcome.recording);
    recording_saved_ = false;
  }
}

void MentorSession::copyCounters(MentorSnapshot& out) const {
  if (!run_) {
    out.ticks = final_counters_.ticks;
    out.overruns = final_counters_.overruns;
    out.faults = final_counters_.faults;
    out.stalls = final_counters_.stalls;
    return;
  }
  const servo::LiveCounters& c = run_->station().loop().counters();
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
  if (phase_ == MentorPhase::kLinked && run_) {
    s.linked_s = run_->watch().linkedFor_s(now);
    s.link_down_now = run_->watch().linkDown();
    s.link_down_s = run_->watch().downFor_s(now);
  }
  return s;
}

wire::UdpEndpoint MentorSession::localEndpoint() const {
  HATTR_DEMAND(run_ != nullptr, "localEndpoint() needs a running session");
  return run_->localEndpoint();
}

const servo::LiveCounters* MentorSession::counters() const noexcept {
  return run_ ? &run_->station().loop().counters() : nullptr;
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
