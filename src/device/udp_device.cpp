#include "hattr/device/udp_device.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/wire/datagram_link.hpp"
#include "hattr/wire/link_session.hpp"

namespace hattr::device {
namespace {

constexpr std::int64_t kHelloRetryNs = 100'000'000;         // handshake: HELLO again after 100 ms
constexpr std::int64_t kRehelloAfterNs = 50'000'000;        // link lost this long: try a new session
constexpr std::int64_t kRehelloIntervalNs = 50'000'000;     // ... every 50 ms
constexpr std::int64_t kIdleNs = 100'000'000;               // reads this far apart: the loop was paused
constexpr std::int64_t kDrainBudgetNs = 250'000;            // a read's network work at most
constexpr std::uint64_t kOffsetWindow = 256;                // RTT samples per clock-offset estimate

struct UdpKey {
  std::string_view key;
  double min;
  double max;
  std::string_view help;
};
constexpr UdpKey kUdpNumberKeys[] = {
    {"hold_ms", 0.5, 20.0, "bridge missing states this long before reporting the link lost [ms]"},
    {"timeout_s", 0.05, 60.0, "how long opening waits for the server's answer [s]"},
};
constexpr std::string_view kUdpKeyList = "key, hold_ms, timeout_s";

}  // namespace

UdpDeviceParams udpDeviceParams(const DeviceUri& uri) {
  const std::string where = fmt::format("udp://{}", uri.target);
  UdpDeviceParams params;
  params.server = wire::parseUdpEndpoint(uri.target, where);
  for (const auto& [key, text] : uri.query) {
    if (key == "key") {
      HATTR_THROW_UNLESS(!text.empty(), "{}: key: expected the path of a key file, got nothing", where);
      params.key_file = text;
      continue;
    }
    const std::string_view name = key;  // clang 14 cannot capture a structured binding
    const auto* spec = std::find_if(std::begin(kUdpNumberKeys), std::end(kUdpNumberKeys),
                                    [name](const UdpKey& k) { return k.key == name; });
    HATTR_THROW_UNLESS(spec != std::end(kUdpNumberKeys), "{}: unknown key \"{}\": expected one of {}", where, key,
                       kUdpKeyList);
    double value = 0.0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    HATTR_THROW_UNLESS(ec == std::errc{} && end == text.data() + text.size() && std::isfinite(value) &&
                           value >= spec->min && value <= spec->max,
                       "{}: key {}: expected a number in [{}, {}], got \"{}\"", where, key, spec->min, spec->max, text);
    if (key == "hold_ms") params.hold_s = value * 1e-3;
    if (key == "timeout_s") params.handshake_timeout_s = value;
  }
  HATTR_THROW_UNLESS(!params.key_file.empty(),
                     "{}: missing key=FILE: expected the shared key file (make one with `hattr device keygen --out "
                     "FILE`; keys never go on the command line)",
                     where);
  return params;
}

/// The client's state behind UdpDevice: the session (wire::InitiatorLinkSession) and what the
/// link did.
class UdpDevice::Impl {
 public:
  enum class Fault : int {
    kNone, kLinkLost, kServerClosed, kServerBusy, kServerDeviceFault, kServerDeviceDisconnected, kServerSafetyFault,
    kServerDeviceChanged
  };

  Impl(const UdpDeviceParams& params, std::string uri_text, HandScript* hand);
  void handshake();
  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept;
  DeviceStatus write(const Vec3& f_on_pen_W) noexcept;
  void takeState() noexcept;
  void followSession() noexcept;
  void measureLink(const wire::PacketHeader& header, std::int64_t arrival_ns) noexcept;
  void setFault(Fault fault, double gap_ms) noexcept {
    fault_gap_ms_.store(gap_ms, std::memory_order_relaxed);
    fault_.store(static_cast<int>(fault), std::memory_order_release);
  }
  static void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

  UdpDeviceParams params_;
  std::string uri_;
  HandScript* hand_;
  std::int64_t hold_ns_;
  wire::UdpDatagramLink link_;
  wire::InitiatorLinkSession session_;
  wire::WelcomePayload device_;  // the first session's WELCOME: the device this side was sized for

  // The newest state and the link's timing (servo thread after the handshake).
  std::uint64_t generation_ = 0;
  wire::StatePayload state_;
  std::int64_t state_sent_ns_ = 0;       // its sender time (server clock)
  std::int64_t state_arrival_ns_ = -1;   // its arrival (client clock); -1: none yet
  std::uint64_t state_sequence_ = 0;
  std::uint64_t used_state_sequence_ = 0;
  std::int64_t last_read_ns_ = -1;
  std::int64_t resume_ns_ = 0;
  std::uint64_t last_echo_sequence_ = 0;
  double loop_time_s_ = 0.0;
  bool device_changed_ = false;          // a reconnection found another device
  Fault ended_by_ = Fault::kNone;        // kServerClosed / kServerBusy: how the last session ended
  std::int64_t best_rtt_ns_ = -1;
  std::int64_t offset_candidate_ns_ = 0;
  std::uint64_t offset_window_ = 0;

  // Readable from other threads.
  std::atomic<int> fault_{0};
  std::atomic<double> fault_gap_ms_{0.0};
  std::atomic<std::int64_t> clock_offset_ns_{0};
  std::atomic<std::uint64_t> commands_sent_{0};
  std::atomic<std::uint64_t> held_reads_{0};
  std::atomic<std::uint64_t> disconnected_reads_{0};
  std::atomic<std::uint64_t> reconnects_{0};
  DurationHistogram rtt_;
  DurationHistogram state_age_;
};

namespace {

/// The same device on both WELCOMEs: every limit, the capabilities, the rate. A reconnection
/// to another device would leave this side's safety path sized for the old one.
bool sameDevice(const wire::WelcomePayload& a, const wire::WelcomePayload& b) noexcept {
  const DeviceLimits& x = a.limits;
  const DeviceLimits& y = b.limits;
  return x.degrees_of_freedom == y.degrees_of_freedom && x.workspace_min_m == y.workspace_min_m &&
         x.workspace_max_m == y.workspace_max_m && x.peak_force_N == y.peak_force_N &&
         x.continuous_force_N == y.continuous_force_N && x.max_stiffness_N_per_m == y.max_stiffness_N_per_m &&
         x.max_damping_N_s_per_m == y.max_damping_N_s_per_m && x.nominal_rate_hz == y.nominal_rate_hz &&
         x.mass_kg == y.mass_kg && x.damping_N_s_per_m == y.damping_N_s_per_m && a.capabilities == b.capabilities &&
         a.rate_hz == b.rate_hz;
}

wire::LinkSessionTiming clientTiming() {
  wire::LinkSessionTiming timing;
  timing.hello_retry_ns = kHelloRetryNs;
  timing.drain_budget_ns = kDrainBudgetNs;
  return timing;
}

}  // namespace

UdpDevice::Impl::Impl(const UdpDeviceParams& params, std::string uri_text, HandScript* hand)
    : params_(params),
      uri_(std::move(uri_text)),
      hand_(hand),
      hold_ns_(units::secondsToNanoseconds(params.hold_s)),
      link_(wire::UdpSocket::connected(params.server), wire::UdpDatagramLink::Clock::kMonotonic),
      session_(wire::readKeyFile(params.key_file), wire::PacketType::kState, link_, params.server, clientTiming()) {}

// The handshake, all before the servo loop exists: HELLO (a COOKIE asks for it again), then
// WELCOME or BUSY, then a zero force every 10 ms until the first STATE.
void UdpDevice::Impl::handshake() {
  const std::string where = fmt::format("udp://{}", params_.server.text());
  const std::int64_t start = wire::monotonicNs();
  const std::int64_t deadline = start + units::secondsToNanoseconds(params_.handshake_timeout_s);
  session_.connect(start);
  std::int64_t next_command = start;
  for (std::int64_t now = start; now < deadline && state_arrival_ns_ < 0; now = wire::monotonicNs()) {
    session_.pump(now);
    HATTR_THROW_UNLESS(session_.state() != wire::InitiatorLinkSession::State::kRefused,
                       "{}: the device server at {} already serves another client", where, params_.server.text());
    takeState();
    // Welcomed: a zero force proves the session; the server streams states only after one.
    if (session_.live() && now >= next_command) {
      (void)write(Vec3::Zero());
      next_command = now + kHelloRetryNs / 10;
    }
    const std::int64_t wake = std::min({deadline, session_.live() ? next_command : session_.lastHello_ns() + kHelloRetryNs});
    (void)link_.waitReadable(std::max<std::int64_t>(0, wake - wire::monotonicNs()));
  }
  const wire::LinkSessionStats stats = session_.stats();
  HATTR_THROW_UNLESS(stats.drops[static_cast<std::size_t>(wire::DropReason::kBadVersion)] == 0 || session_.live(),
                     "{}: the device server at {} speaks another version of the hattr protocol (this client speaks "
                     "version {}); run the same hattr release on both machines",
                     where, params_.server.text(), wire::kProtocolVersion);
  HATTR_THROW_UNLESS(session_.live(),
                     "{}: no answer from a hattr device server within {} s{}; a server with another key drops the "
                     "hello unanswered, so a wrong key file looks like this too",
                     where, params_.handshake_timeout_s,
                     link_.refused() ? " (the host refused: nothing listens on that port)" : "");
  if (state_arrival_ns_ < 0) {
    throw Error(fmt::format("{}: the device server welcomed this client but sent no pen state within {} s", where,
                            params_.handshake_timeout_s));
  }
  device_ = session_.welcome();
  generation_ = session_.generation();
  // The server's limits size this side's safety path and gain clamps: checked like a file.
  checkReportedLimits(device_.limits, where + ": the device server");
  resume_ns_ = state_arrival_ns_;
}

// A new session after the first: counted, and refused as a fault if the device differs.
void UdpDevice::Impl::followSession() noexcept {
  const std::uint64_t generation = session_.generation();
  if (generation == generation_) return;
  generation_ = generation;
  last_echo_sequence_ = 0;
  ended_by_ = Fault::kNone;
  bump(reconnects_);
  if (!sameDevice(session_.welcome(), device_)) device_changed_ = true;
}

void UdpDevice::Impl::takeState() noexcept {
  wire::Packet packet;
  std::int64_t arrival_ns = 0;
  if (!session_.takeData(packet, arrival_ns)) return;
  state_ = std::get<wire::StatePayload>(packet.payload);
  state_sent_ns_ = packet.header.sender_time_ns;
  state_arrival_ns_ = arrival_ns;
  state_sequence_ = packet.header.sequence;
  measureLink(packet.header, arrival_ns);
}

// Round trip and clock offset from the echo of our newest command (NTP's four stamps:
// t1 command sent, t2 = t3 − hold its arrival, t3 this state sent, t4 its arrival). Every
// difference is checked: the fields are authentic, not necessarily sane.
void UdpDevice::Impl::measureLink(const wire::PacketHeader& header, std::int64_t arrival_ns) noexcept {
  if (state_.echo_sequence <= last_echo_sequence_) return;
  last_echo_sequence_ = state_.echo_sequence;
  const std::int64_t t1 = state_.echo_sender_time_ns;
  const std::int64_t t3 = header.sender_time_ns;
  const std::int64_t t4 = arrival_ns;
  if (t1 <= 0 || t1 > t4 || state_.hold_ns > t4 - t1) return;
  const std::int64_t rtt = (t4 - t1) - state_.hold_ns;
  rtt_.record(rtt);
  const std::int64_t offset = (t3 - state_.hold_ns - t1) / 2 + (t3 - t4) / 2;
  if (best_rtt_ns_ < 0 || rtt < best_rtt_ns_) {
    best_rtt_ns_ = rtt;
    offset_candidate_ns_ = offset;
  }
  // The lowest-RTT exchange of each window is the least disturbed by queueing.
  if (++offset_window_ == 1 || offset_window_ % kOffsetWindow == 0) {
    clock_offset_ns_.store(offset_candidate_ns_, std::memory_order_relaxed);
    if (offset_window_ != 1) best_rtt_ns_ = -1;
  }
}

DeviceStatus UdpDevice::Impl::read(std::chrono::nanoseconds now, PenState& out) noexcept {
  const std::int64_t mono = wire::monotonicNs();
  // Reads far apart mean the loop was paused (before a trial, between trials): the link is
  // judged from now on. A late read of a running loop (an overrun) restarts nothing.
  if (last_read_ns_ < 0 || mono - last_read_ns_ > kIdleNs) resume_ns_ = mono;
  last_read_ns_ = mono;
  loop_time_s_ = std::chrono::duration<double>(now).count();
  session_.pump(mono);
  followSession();
  takeState();

  out = state_.pen;
  out.t_s = loop_time_s_;
  // How the session ended (a BYE, a BUSY to a new hello) holds until a new one opens.
  using State = wire::InitiatorLinkSession::State;
  const State state = session_.state();
  if (state == State::kRefused) ended_by_ = Fault::kServerBusy;
  if (state == State::kClosed) ended_by_ = Fault::kServerClosed;
  const bool busy = ended_by_ == Fault::kServerBusy;
  const bool closed = ended_by_ == Fault::kServerClosed;
  const std::int64_t gap = mono - std::max(state_arrival_ns_, resume_ns_);
  if (busy || closed || gap > hold_ns_) {
    bump(disconnected_reads_);
    setFault(ended_by_ != Fault::kNone ? ended_by_ : Fault::kLinkLost, static_cast<double>(mono - state_arrival_ns_) * 1e-6);
    // Say hello again (a restarted server, a timed-out session): recovery without a restart.
    if (mono - session_.lastHello_ns() >= kRehelloIntervalNs &&
        (mono - state_arrival_ns_ >= kRehelloAfterNs || closed || busy)) {
      session_.connect(mono);
    }
    return DeviceStatus::kDisconnected;
  }

  // Bridging: the same state as last time (counted).
  if (state_sequence_ == used_state_sequence_) {
    bump(held_reads_);
  } else {
    used_state_sequence_ = state_sequence_;
  }
  if (offset_window_ > 0) {
    const std::int64_t age = mono - state_sent_ns_ + clock_offset_ns_.load(std::memory_order_relaxed);
    if (age >= 0) state_age_.record(age);
  }
  if (device_changed_) {
    setFault(Fault::kServerDeviceChanged, 0.0);
    return DeviceStatus::kFault;
  }
  if ((state_.server_flags & wire::kServerSafetyFault) != 0) {
    setFault(Fault::kServerSafetyFault, 0.0);
    return DeviceStatus::kFault;
  }
  if (state_.device_status != DeviceStatus::kOk) {
    setFault(state_.device_status == DeviceStatus::kFault ? Fault::kServerDeviceFault
                                                          : Fault::kServerDeviceDisconnected,
             0.0);
    return state_.device_status;
  }
  return DeviceStatus::kOk;
}

DeviceStatus UdpDevice::Impl::write(const Vec3& f_on_pen_W) noexcept {
  const bool finite = f_on_pen_W.allFinite();
  wire::CommandPayload command;
  command.f_on_pen_W = finite ? f_on_pen_W : Vec3(Vec3::Zero());
  if (hand_ != nullptr) {
    command.has_hand = true;
    command.hand = hand_->command(loop_time_s_);
  }
  if (session_.send(command, wire::monotonicNs())) bump(commands_sent_);
  return finite ? DeviceStatus::kOk : DeviceStatus::kFault;
}

UdpDevice::UdpDevice(const UdpDeviceParams& params, std::string uri_text, HandScript* hand)
    : impl_(std::make_unique<Impl>(params, std::move(uri_text), hand)) {
  impl_->handshake();
}

UdpDevice::~UdpDevice() { impl_->session_.close(wire::monotonicNs()); }

DeviceStatus UdpDevice::read(std::chrono::nanoseconds now, PenState& out) noexcept { return impl_->read(now, out); }
DeviceStatus UdpDevice::write(const Vec3& f_on_pen_W) noexcept { return impl_->write(f_on_pen_W); }
const DeviceLimits& UdpDevice::limits() const noexcept { return impl_->device_.limits; }
DeviceCapabilities UdpDevice::capabilities() const noexcept { return impl_->device_.capabilities; }
const std::string& UdpDevice::uri() const noexcept { return impl_->uri_; }
double UdpDevice::serverRate_hz() const noexcept { return impl_->device_.rate_hz; }

std::string UdpDevice::faultReason() const {
  const std::string server = impl_->params_.server.text();
  const double gap_ms = impl_->fault_gap_ms_.load(std::memory_order_relaxed);
  using Fault = Impl::Fault;
  switch (static_cast<Fault>(impl_->fault_.load(std::memory_order_acquire))) {
    case Fault::kNone: return {};
    case Fault::kLinkLost: return fmt::format("link lost: no state from {} for {:.1f} ms", server, gap_ms);
    case Fault::kServerClosed: return fmt::format("link lost: the device server at {} ended the session", server);
    case Fault::kServerBusy:
      return fmt::format("link lost: the device server at {} now serves another client", server);
    case Fault::kServerDeviceFault: return fmt::format("the device server at {} reports a fault of its device", server);
    case Fault::kServerDeviceDisconnected:
      return fmt::format("the device server at {} reports its device disconnected", server);
    case Fault::kServerSafetyFault:
      return fmt::format("the device server at {} latched a fault in its safety path (zero force there)", server);
    case Fault::kServerDeviceChanged:
      return fmt::format(
          "the device server at {} came back with another device (limits, capabilities or rate differ); reopen the "
          "device",
          server);
  }
  return {};
}

LinkStats UdpDevice::linkStats() const {
  const Impl& i = *impl_;
  const wire::LinkSessionStats session = i.session_.stats();
  LinkStats s;
  s.rtt = i.rtt_;
  s.state_age = i.state_age_;
  s.clock_offset_ns = i.clock_offset_ns_.load(std::memory_order_relaxed);
  s.commands_sent = i.commands_sent_.load(std::memory_order_relaxed);
  s.states_received = session.data_received;
  s.states_lost = session.data_lost;
  s.states_late = session.drops[static_cast<std::size_t>(wire::DropReason::kOutOfOrder)];
  s.held_reads = i.held_reads_.load(std::memory_order_relaxed);
  s.disconnected_reads = i.disconnected_reads_.load(std::memory_order_relaxed);
  s.reconnects = i.reconnects_.load(std::memory_order_relaxed);
  s.cookies = session.cookies;
  s.drops = session.drops;
  return s;
}

std::unique_ptr<Device> openUdpDevice(const DeviceUri& uri, std::string_view uri_text, HandScript* hand) {
  return std::make_unique<UdpDevice>(udpDeviceParams(uri), std::string(uri_text), hand);
}

std::string udpDeviceHelp() {
  std::string text =
      "udp://HOST:PORT keys (a pen served by `hattr device serve`; HOST an IPv4 address or localhost):\n"
      "  key                      the shared key file, 64 hex characters (`hattr device keygen`); required\n";
  // Each key's default is the parameters' own default, in the key's unit.
  const UdpDeviceParams defaults;
  static_assert(std::size(kUdpNumberKeys) == 2, "a new key needs its default here");
  for (const auto& k : kUdpNumberKeys) {
    const double fallback = k.key == "hold_ms" ? defaults.hold_s * 1e3 : defaults.handshake_timeout_s;
    text += fmt::format("  {:<24} {} in [{}, {}], default {}\n", k.key, k.help, k.min, k.max, fallback);
  }
  return text;
}

}  // namespace hattr::device
