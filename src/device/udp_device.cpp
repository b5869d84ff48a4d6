#include "hattr/device/udp_device.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::device {
namespace {

constexpr std::size_t kMaxDrain = 64;                       // datagrams per read(): bounds a tick's work
constexpr std::int64_t kHelloRetryNs = 100'000'000;         // handshake: HELLO again after 100 ms
constexpr std::int64_t kRehelloAfterNs = 50'000'000;        // link lost this long: try a new session
constexpr std::int64_t kRehelloIntervalNs = 50'000'000;     // ... every 50 ms
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

double ms(std::int64_t ns) noexcept { return static_cast<double>(ns) * 1e-6; }

}  // namespace

UdpDeviceParams udpDeviceParams(const DeviceUri& uri) {
  const std::string where = fmt::format("udp://{}", uri.target);
  UdpDeviceParams params;
  params.server = net::parseUdpEndpoint(uri.target, where);
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

// The handshake: HELLO (retried every 100 ms with the same nonce), WELCOME or BUSY, then
// the first STATE, all before the servo loop exists.
UdpDevice::UdpDevice(const UdpDeviceParams& params, std::string uri_text, HandScript* hand)
    : params_(params),
      uri_(std::move(uri_text)),
      hand_(hand),
      key_(net::readKeyFile(params.key_file)),
      socket_(net::UdpSocket::connected(params.server)),
      hold_ns_(static_cast<std::int64_t>(std::llround(params.hold_s * 1e9))) {
  const std::string where = fmt::format("udp://{}", params_.server.text());
  random_.fill(pending_nonce_);
  hello_pending_ = true;
  const std::int64_t start = net::monotonicNs();
  const std::int64_t deadline = start + static_cast<std::int64_t>(std::llround(params_.handshake_timeout_s * 1e9));
  std::int64_t next_hello = start;
  std::int64_t next_command = start;
  bool refused = false;
  for (std::int64_t now = start; now < deadline && state_arrival_ns_ < 0; now = net::monotonicNs()) {
    if (session_id_ == 0 && now >= next_hello) {
      sendHello(now);
      next_hello = now + kHelloRetryNs;
    }
    // Welcomed: a zero force proves the session; the server streams states only after one.
    if (session_id_ != 0 && now >= next_command) {
      (void)write(Vec3::Zero());
      next_command = now + kHelloRetryNs / 10;
    }
    const std::int64_t wake = session_id_ != 0 ? std::min(deadline, next_command) : std::min(deadline, next_hello);
    (void)socket_.waitReadable(std::max<std::int64_t>(0, wake - now));
    net::Received rx;
    for (std::size_t i = 0; i < kMaxDrain; ++i) {
      const auto status = socket_.receive(rx_buffer_, rx);
      if (status == net::ReceiveStatus::kRefused) refused = true;
      if (status != net::ReceiveStatus::kPacket) break;
      net::Packet packet;
      net::DropReason why{};
      if (rx.size > rx_buffer_.size() ||
          !net::decodePacket(std::span(rx_buffer_.data(), rx.size), key_, packet, why)) {
        drops_.count(rx.size > rx_buffer_.size() ? net::DropReason::kBadSize : why);
        continue;
      }
      handle(packet, rx);
    }
    HATTR_THROW_UNLESS(!server_busy_, "{}: the device server at {} already serves another client", where,
                       params_.server.text());
  }
  HATTR_THROW_UNLESS(session_id_ != 0,
                     "{}: no answer from a hattr device server within {} s{}; a server with another key drops the "
                     "hello unanswered, so a wrong key file looks like this too",
                     where, params_.handshake_timeout_s,
                     refused ? " (the host refused: nothing listens on that port)" : "");
  if (state_arrival_ns_ < 0) {
    throw Error(fmt::format("{}: the device server welcomed this client but sent no pen state within {} s", where,
                            params_.handshake_timeout_s));
  }
  // The server's limits size this side's safety path and gain clamps: checked like a file.
  checkReportedLimits(welcome_.limits, where + ": the device server");
  resume_ns_ = state_arrival_ns_;
}

UdpDevice::~UdpDevice() {
  if (session_id_ == 0) return;
  const net::Packet bye{{.session_id = session_id_, .sequence = ++send_sequence_, .sender_time_ns = net::monotonicNs()},
                        net::ByePayload{}};
  (void)socket_.send(std::span(tx_buffer_.data(), net::encodePacket(bye, key_, tx_buffer_)));
}

void UdpDevice::sendHello(std::int64_t now_ns) noexcept {
  const net::Packet hello{{.session_id = 0, .sequence = ++send_sequence_, .sender_time_ns = now_ns},
                          net::HelloPayload{pending_nonce_}};
  (void)socket_.send(std::span(tx_buffer_.data(), net::encodePacket(hello, key_, tx_buffer_)));
  last_hello_ns_ = now_ns;
}

void UdpDevice::setFault(Fault fault, double gap_ms) noexcept {
  fault_gap_ms_.store(gap_ms, std::memory_order_relaxed);
  fault_.store(static_cast<int>(fault), std::memory_order_release);
}

// Every datagram waiting (bounded): authentic packets of the session are handled, the
// rest counted by reason.
void UdpDevice::drain() noexcept {
  net::Received rx;
  for (std::size_t i = 0; i < kMaxDrain; ++i) {
    if (socket_.receive(rx_buffer_, rx) != net::ReceiveStatus::kPacket) break;
    net::Packet packet;
    net::DropReason why{};
    if (rx.size > rx_buffer_.size()) {
      drops_.count(net::DropReason::kBadSize);
      continue;
    }
    if (!net::decodePacket(std::span(rx_buffer_.data(), rx.size), key_, packet, why)) {
      drops_.count(why);
      continue;
    }
    handle(packet, rx);
  }
}

void UdpDevice::handle(const net::Packet& packet, const net::Received& rx) noexcept {
  const net::PacketHeader& h = packet.header;
  net::DropReason why{};
  switch (h.type) {
    // A new session: only for the hello we are waiting for.
    case net::PacketType::kWelcome: {
      const auto& welcome = std::get<net::WelcomePayload>(packet.payload);
      if (!hello_pending_ || welcome.client_nonce != pending_nonce_ || h.session_id == 0) {
        drops_.count(net::DropReason::kUnexpected);
        return;
      }
      if (session_id_ == 0) {
        welcome_ = welcome;
      } else {
        bump(reconnects_);
        // A reconnection to a server whose device differs would leave this side's safety
        // path sized for the old one: refused, as a fault.
        if (!(welcome.limits.peak_force_N == welcome_.limits.peak_force_N &&
              welcome.limits.continuous_force_N == welcome_.limits.continuous_force_N &&
              welcome.limits.max_stiffness_N_per_m == welcome_.limits.max_stiffness_N_per_m &&
              welcome.limits.max_damping_N_s_per_m == welcome_.limits.max_damping_N_s_per_m &&
              welcome.limits.nominal_rate_hz == welcome_.limits.nominal_rate_hz &&
              welcome.limits.workspace_min_m == welcome_.limits.workspace_min_m &&
              welcome.limits.workspace_max_m == welcome_.limits.workspace_max_m)) {
          limits_changed_ = true;
        }
      }
      session_id_ = h.session_id;
      send_sequence_ = 0;
      lost_previous_sessions_ += state_sequence_.lost();
      state_sequence_.reset();
      (void)state_sequence_.accept(h.sequence, why);
      last_echo_sequence_ = 0;
      hello_pending_ = false;
      server_closed_ = false;
      server_busy_ = false;
      return;
    }
    case net::PacketType::kBusy: {
      const auto& busy = std::get<net::BusyPayload>(packet.payload);
      if (!hello_pending_ || busy.client_nonce != pending_nonce_) {
        drops_.count(net::DropReason::kUnexpected);
        return;
      }
      hello_pending_ = false;
      server_busy_ = true;
      return;
    }
    case net::PacketType::kState:
    case net::PacketType::kBye: break;
    default: drops_.count(net::DropReason::kUnexpected); return;
  }

  // STATE and BYE: of this session, newer than anything accepted.
  if (session_id_ == 0 || h.session_id != session_id_) {
    drops_.count(net::DropReason::kWrongSession);
    return;
  }
  if (!state_sequence_.accept(h.sequence, why)) {
    drops_.count(why);
    return;
  }
  states_lost_.store(lost_previous_sessions_ + state_sequence_.lost(), std::memory_order_relaxed);
  if (h.type == net::PacketType::kBye) {
    server_closed_ = true;
    return;
  }
  bump(states_received_);
  state_ = std::get<net::StatePayload>(packet.payload);
  state_sent_ns_ = h.sender_time_ns;
  state_arrival_ns_ = rx.arrival_ns;

  // Round trip and clock offset from the echo of our newest command (NTP's four stamps:
  // t1 command sent, t2 = t3 − hold its arrival, t3 this state sent, t4 its arrival).
  if (state_.echo_sequence > last_echo_sequence_) {
    last_echo_sequence_ = state_.echo_sequence;
    const std::int64_t t1 = state_.echo_sender_time_ns;
    const std::int64_t t3 = h.sender_time_ns;
    const std::int64_t t4 = rx.arrival_ns;
    const std::int64_t rtt = (t4 - t1) - state_.hold_ns;
    if (rtt >= 0) {
      rtt_.record(rtt);
      const std::int64_t offset = ((t3 - state_.hold_ns - t1) + (t3 - t4)) / 2;
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
  }
}

DeviceStatus UdpDevice::read(std::chrono::nanoseconds now, PenState& out) noexcept {
  const std::int64_t mono = net::monotonicNs();
  // After a pause in polling (or the first read), the link is judged from now on: what
  // piled up or was missed while nobody read is not the link's fault.
  if (last_read_ns_ < 0 || mono - last_read_ns_ > hold_ns_) resume_ns_ = mono;
  last_read_ns_ = mono;
  loop_time_s_ = std::chrono::duration<double>(now).count();
  drain();

  out = state_.pen;
  out.t_s = loop_time_s_;
  const std::int64_t gap = mono - std::max(state_arrival_ns_, resume_ns_);
  if (server_busy_ || server_closed_ || gap > hold_ns_) {
    bump(disconnected_reads_);
    setFault(server_busy_ ? Fault::kServerBusy : server_closed_ ? Fault::kServerClosed : Fault::kLinkLost,
             ms(mono - state_arrival_ns_));
    // Say hello again (a restarted server, a timed-out session): recovery without a restart.
    const std::int64_t since_state = mono - state_arrival_ns_;
    if (mono - last_hello_ns_ >= kRehelloIntervalNs &&
        (since_state >= kRehelloAfterNs || server_closed_ || server_busy_)) {
      random_.fill(pending_nonce_);
      hello_pending_ = true;
      server_busy_ = false;
      sendHello(mono);
    }
    return DeviceStatus::kDisconnected;
  }

  // Bridging: the same state as last time (counted).
  if (state_sequence_.newest() == used_state_sequence_) {
    bump(held_reads_);
  } else {
    used_state_sequence_ = state_sequence_.newest();
  }
  if (offset_window_ > 0) {
    state_age_.record(mono - (state_sent_ns_ - clock_offset_ns_.load(std::memory_order_relaxed)));
  }
  if (limits_changed_) {
    setFault(Fault::kServerLimitsChanged, 0.0);
    return DeviceStatus::kFault;
  }
  if ((state_.server_flags & net::kServerSafetyFault) != 0) {
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

DeviceStatus UdpDevice::write(const Vec3& f_on_pen_W) noexcept {
  const bool finite = f_on_pen_W.allFinite();
  net::CommandPayload command;
  command.f_on_pen_W = finite ? f_on_pen_W : Vec3(Vec3::Zero());
  if (hand_ != nullptr) {
    command.has_hand = true;
    command.hand = hand_->command(loop_time_s_);
  }
  const net::Packet packet{
      {.session_id = session_id_, .sequence = ++send_sequence_, .sender_time_ns = net::monotonicNs()}, command};
  if (socket_.send(std::span(tx_buffer_.data(), net::encodePacket(packet, key_, tx_buffer_)))) bump(commands_sent_);
  return finite ? DeviceStatus::kOk : DeviceStatus::kFault;
}

std::string UdpDevice::faultReason() const {
  const std::string server = params_.server.text();
  const double gap_ms = fault_gap_ms_.load(std::memory_order_relaxed);
  switch (static_cast<Fault>(fault_.load(std::memory_order_acquire))) {
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
    case Fault::kServerLimitsChanged:
      return fmt::format("the device server at {} came back with a device of other limits; reopen the device", server);
  }
  return {};
}

LinkStats UdpDevice::linkStats() const {
  LinkStats s;
  s.rtt = rtt_;
  s.state_age = state_age_;
  s.clock_offset_ns = clock_offset_ns_.load(std::memory_order_relaxed);
  s.commands_sent = commands_sent_.load(std::memory_order_relaxed);
  s.states_received = states_received_.load(std::memory_order_relaxed);
  s.states_lost = states_lost_.load(std::memory_order_relaxed);
  s.states_late = drops_[net::DropReason::kOutOfOrder];
  s.held_reads = held_reads_.load(std::memory_order_relaxed);
  s.disconnected_reads = disconnected_reads_.load(std::memory_order_relaxed);
  s.reconnects = reconnects_.load(std::memory_order_relaxed);
  for (std::size_t i = 0; i < net::kDropReasonCount; ++i) s.drops[i] = drops_[static_cast<net::DropReason>(i)];
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
