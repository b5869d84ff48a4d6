#include "hattr/device/serial_device.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/openpen/protocol.h"
#include "serial_port_internal.hpp"

namespace hattr::device {
namespace {

using Clock = std::chrono::steady_clock;

/// Counts a dropped packet; wraps never (the counters are 64-bit).
void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

double parseNumber(const DeviceUri& uri, const std::string& key, const std::string& text, double min, double max) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  HATTR_THROW_UNLESS(ec == std::errc{} && end == text.data() + text.size() && std::isfinite(value) && value >= min &&
                         value <= max,
                     "serial://{}: key {}: expected a number in [{}, {}], got \"{}\"", uri.target, key, min, max, text);
  return value;
}

/// The pen's IDENTITY as a spec, every constant checked; all problems at once.
PlanarPenSpec specFromIdentity(const hpen_identity& id, std::string_view who) {
  std::vector<std::string> problems;
  const auto expect = [&problems](bool ok, std::string text) {
    if (!ok) problems.push_back(std::move(text));
  };
  const auto positive = [](double v, double max) { return std::isfinite(v) && v > 0.0 && v <= max; };
  expect(positive(id.base_separation_m, 1.0), fmt::format("base separation: expected (0, 1] m, got {}", id.base_separation_m));
  expect(positive(id.proximal_m, 1.0), fmt::format("proximal link: expected (0, 1] m, got {}", id.proximal_m));
  expect(positive(id.distal_m, 1.0), fmt::format("distal link: expected (0, 1] m, got {}", id.distal_m));
  expect(std::isfinite(id.home_q0_rad) && std::isfinite(id.home_q1_rad), "home pose: expected finite joint angles");
  expect(id.counts_per_joint_rev > 0, "counts per joint turn: expected more than 0, got 0");
  expect(positive(id.peak_torque_Nm, 100.0), fmt::format("peak torque: expected (0, 100] N·m, got {}", id.peak_torque_Nm));
  expect(positive(id.continuous_torque_Nm, id.peak_torque_Nm),
         fmt::format("continuous torque: expected (0, peak {}] N·m, got {}", id.peak_torque_Nm, id.continuous_torque_Nm));
  expect(positive(id.sensor_N_per_count, 10.0), fmt::format("sensor: expected (0, 10] N a count, got {}", id.sensor_N_per_count));
  expect(id.sensor_zero_count < id.sensor_max_count,
         fmt::format("sensor: expected its zero ({}) under its full scale ({})", id.sensor_zero_count, id.sensor_max_count));
  expect(id.state_rate_hz >= 100 && id.state_rate_hz <= 10000,
         fmt::format("state rate: expected 100 to 10000 Hz, got {}", id.state_rate_hz));
  expect(id.watchdog_ms >= 1 && id.watchdog_ms <= 1000, fmt::format("watchdog: expected 1 to 1000 ms, got {}", id.watchdog_ms));
  if (!problems.empty()) {
    throw InputError(fmt::format("{}: the pen's IDENTITY is not usable ({} problems):\n  {}", who, problems.size(),
                                 fmt::join(problems, "\n  ")));
  }
  PlanarPenSpec spec;
  spec.model = std::string(id.model, strnlen(id.model, HPEN_MODEL_BYTES));
  spec.firmware_build = id.firmware_build;
  spec.geometry = {.base_separation_m = id.base_separation_m, .proximal_m = id.proximal_m, .distal_m = id.distal_m};
  spec.home_q = Vec2(id.home_q0_rad, id.home_q1_rad);
  spec.counts_per_joint_rev = id.counts_per_joint_rev;
  spec.peak_torque_Nm = id.peak_torque_Nm;
  spec.continuous_torque_Nm = id.continuous_torque_Nm;
  spec.sensor_N_per_count = id.sensor_N_per_count;
  spec.sensor_zero_count = id.sensor_zero_count;
  spec.sensor_max_count = id.sensor_max_count;
  spec.motor_sign = id.motor_sign;
  spec.rate_hz = id.state_rate_hz;
  spec.watchdog_s = id.watchdog_ms * 1e-3;
  // The paper's origin: where the pen is at the home pose.
  HATTR_THROW_UNLESS(fiveBarForward(spec.geometry, spec.home_q, spec.mount.paper_origin_D),
                     "{}: the pen's home pose puts its links where they cannot meet (joint angles {} and {} rad)", who,
                     id.home_q0_rad, id.home_q1_rad);
  return spec;
}

}  // namespace

SerialDeviceParams serialDeviceParams(const DeviceUri& uri) {
  SerialDeviceParams params;
  HATTR_THROW_UNLESS(!uri.target.empty(), "serial://: expected a port, e.g. serial:///dev/ttyACM0");
  params.port = uri.target;
  for (const auto& [key, text] : uri.query) {
    if (key == "baud") {
      params.baud = static_cast<unsigned>(parseNumber(uri, key, text, 1.0, 1e7));
      HATTR_THROW_UNLESS(SerialPort::baudSupported(params.baud) && std::to_string(params.baud) == text,
                         "serial://{}: key baud: expected one of {}, got \"{}\"", uri.target, SerialPort::supportedBauds(), text);
    } else if (key == "home") {
      HATTR_THROW_UNLESS(text == "once" || text == "always" || text == "never",
                         "serial://{}: key home: expected once, always or never, got \"{}\"", uri.target, text);
      params.homing = text == "once"     ? SerialDeviceParams::Homing::kOnce
                      : text == "always" ? SerialDeviceParams::Homing::kAlways
                                         : SerialDeviceParams::Homing::kNever;
    } else if (key == "timeout_s") {
      params.handshake_timeout_s = parseNumber(uri, key, text, 0.01, 60.0);
    } else if (key == "velocity_hz") {
      params.velocity_cutoff_hz = parseNumber(uri, key, text, 1.0, 1000.0);
    } else if (key == "contact_N") {
      params.contact_N = parseNumber(uri, key, text, 0.0, 10.0);
    } else if (key == "state_timeout_s") {
      params.state_timeout_s = parseNumber(uri, key, text, 0.001, 60.0);
    } else if (key == "lockstep") {
      HATTR_THROW_UNLESS(text == "0" || text == "1", "serial://{}: key lockstep: expected 0 or 1, got \"{}\"", uri.target, text);
      params.lockstep = text == "1";
    } else if (key == "max_force_N") {
      params.max_force_N = parseNumber(uri, key, text, 0.01, 100.0);
    } else {
      throw InputError(fmt::format("serial://{}: unknown key \"{}\": expected one of baud, home, timeout_s, velocity_hz, "
                                   "contact_N, state_timeout_s, lockstep, max_force_N",
                                   uri.target, key));
    }
  }
  return params;
}

// ---- the device's state: the handshake's results, the reader thread, the servo thread's view ----

class SerialDevice::Impl {
 public:
  Impl(const SerialDeviceParams& params, std::string uri)
      : params_(params), uri_(std::move(uri)), port_(params.port, params.baud) {
    hpen_parser_reset(&parser_);
    handshake();
    HATTR_THROW_UNLESS(homed_ || params_.homing != SerialDeviceParams::Homing::kNever,
                       "{}: the pen has not been homed since it was powered up, and home=never keeps its counts from "
                       "power-up: rest the linkage at its home pose and use home=once (the default) or home=always",
                       uri_);
    try {
      limits_ = planarPenLimits(spec_);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}", uri_, e.what()));
    }
    if (params_.max_force_N > 0.0) {
      limits_.peak_force_N = std::min(limits_.peak_force_N, params_.max_force_N);
      limits_.continuous_force_N = std::min(limits_.continuous_force_N, limits_.peak_force_N);
    }
    checkReportedLimits(limits_, uri_ + ": the pen");
  }

  ~Impl() { stopClock(); }

  void handshake();
  void startClock(DeviceTickFn tick, void* context);
  void stopClock() noexcept;
  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept;
  DeviceStatus write(const Vec3& f_on_pen_W) noexcept;
  std::string faultReason() const;
  SerialCounters counters() const noexcept;
  /// No STATE this long: the link is lost (the URI's, else 60 s in lockstep, else the pen's watchdog time).
  double stateTimeout_s() const noexcept {
    return params_.state_timeout_s > 0.0 ? params_.state_timeout_s : params_.lockstep ? 60.0 : spec_.watchdog_s;
  }

  SerialDeviceParams params_;
  std::string uri_;
  SerialPort port_;
  PlanarPenSpec spec_;
  DeviceLimits limits_;
  bool homed_ = false;  // the pen's encoders count from its home pose
  hpen_parser parser_{};

  // The reader thread.
  std::thread reader_;
  std::atomic<bool> stopping_{false};
  DeviceTickFn tick_ = nullptr;
  void* tick_context_ = nullptr;
  void readLoop() noexcept;
  void takeState(const hpen_state& s) noexcept;
  void disconnect(int reason) noexcept;

  // The servo thread's view (the reader thread calls the tick, so it is that thread).
  PenState pen_;
  Vec2 q_ = Vec2::Zero();
  bool have_state_ = false;
  bool have_first_ = false;
  std::uint32_t last_time_us_ = 0;
  std::int64_t device_time_us_ = 0;  // since the first STATE after START
  std::uint16_t last_seq_ = 0;
  bool impossible_pose_ = false;

  // Read from any thread.
  std::atomic<bool> disconnected_{false};
  std::atomic<int> fault_{0};
  std::atomic<std::uint64_t> states_{0}, malformed_{0}, out_of_sequence_{0}, wrong_version_{0}, lost_states_{0},
      unsent_{0};
  std::atomic<std::uint32_t> device_counts_[5] = {};
  std::atomic<std::int32_t> last_efforts_{0};
};

namespace {
enum Fault : int { kNoFault = 0, kPortClosed, kNoState, kImpossiblePose };
}  // namespace

void SerialDevice::Impl::handshake() {
  // HELLO every 100 ms until the IDENTITY answering our nonce comes (a board that resets on
  // open answers only once its boot loader has handed over). An emulator in lockstep gets one
  // HELLO: a second one, sent when the wall clock says, would reach it at another simulated time.
  std::mt19937 random(std::random_device{}());
  const hpen_hello hello{.nonce = static_cast<std::uint32_t>(random())};
  std::uint8_t payload[HPEN_HELLO_BYTES];
  hpen_encode_hello(payload, &hello);
  std::uint8_t frame[HPEN_MAX_FRAME_BYTES];
  const std::uint8_t length = hpen_frame(frame, HPEN_PROTOCOL_VERSION, HPEN_HELLO, payload, HPEN_HELLO_BYTES);
  const auto deadline = Clock::now() + std::chrono::duration<double>(params_.handshake_timeout_s);
  auto next_hello = Clock::now();
  while (Clock::now() < deadline) {
    if (Clock::now() >= next_hello) {
      (void)port_.write(frame, length);
      next_hello = params_.lockstep ? Clock::time_point::max() : next_hello + std::chrono::milliseconds(100);
    }
    std::uint8_t buffer[256];
    std::size_t n = 0;
    const auto wait = port_.read(10, buffer, sizeof buffer, n);
    HATTR_THROW_UNLESS(wait != SerialPort::Wait::kClosed, "{}: the port closed during the handshake", uri_);
    for (std::size_t i = 0; i < n; ++i) {
      const hpen_event event = hpen_parser_feed(&parser_, buffer[i]);
      const std::uint8_t type = hpen_parser_type(&parser_);
      if (event == HPEN_WRONG_VERSION && type == HPEN_IDENTITY) {
        throw InputError(fmt::format("{}: the pen speaks protocol version {}, this hattr speaks version {}: update the "
                                     "firmware or hattr so that both match",
                                     uri_, hpen_parser_version(&parser_), HPEN_PROTOCOL_VERSION));
      }
      if (event != HPEN_FRAME || type != HPEN_IDENTITY) continue;
      hpen_identity id{};
      hpen_decode_identity(hpen_parser_payload(&parser_), &id);
      if (id.nonce != hello.nonce) continue;  // an answer to someone's earlier HELLO
      spec_ = specFromIdentity(id, uri_);
      homed_ = (id.status & HPEN_IDENTITY_HOMED) != 0;
      return;
    }
  }
  throw InputError(fmt::format("{}: no IDENTITY from the pen within {} s: is the open pen's firmware on it, at {} baud?",
                               uri_, params_.handshake_timeout_s, params_.baud));
}

void SerialDevice::Impl::startClock(DeviceTickFn tick, void* context) {
  HATTR_DEMAND(!reader_.joinable(), "startClock on {} twice", uri_);
  tick_ = tick;
  tick_context_ = context;
  have_state_ = false;
  have_first_ = false;
  disconnected_.store(false, std::memory_order_release);
  fault_.store(kNoFault, std::memory_order_release);
  using Homing = SerialDeviceParams::Homing;
  const bool zero = params_.homing == Homing::kAlways || (params_.homing == Homing::kOnce && !homed_);
  const hpen_start start{.flags = static_cast<std::uint8_t>(zero ? HPEN_START_ZERO_ENCODERS : 0u)};
  std::uint8_t payload[HPEN_START_BYTES];
  hpen_encode_start(payload, &start);
  std::uint8_t frame[HPEN_MAX_FRAME_BYTES];
  const std::uint8_t length = hpen_frame(frame, HPEN_PROTOCOL_VERSION, HPEN_START, payload, HPEN_START_BYTES);
  HATTR_THROW_UNLESS(port_.write(frame, length), "{}: cannot send START: the port is gone", uri_);
  homed_ = homed_ || zero;
  stopping_.store(false, std::memory_order_release);
  reader_ = std::thread([this] { readLoop(); });
}

void SerialDevice::Impl::stopClock() noexcept {
  if (!reader_.joinable()) return;
  stopping_.store(true, std::memory_order_release);
  reader_.join();
  std::uint8_t payload[HPEN_STOP_BYTES] = {};
  std::uint8_t frame[HPEN_MAX_FRAME_BYTES];
  const std::uint8_t length = hpen_frame(frame, HPEN_PROTOCOL_VERSION, HPEN_STOP, payload, HPEN_STOP_BYTES);
  (void)port_.write(frame, length);
}

// The pen's clock: one tick per STATE. Without STATEs for the watchdog time, or with the port
// gone, the loop is told once (kDisconnected, zero force) and then ticks on the host's clock.
void SerialDevice::Impl::readLoop() noexcept {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / spec_.rate_hz));
  const double timeout_s = stateTimeout_s();
  const auto watchdog = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  auto last_state = Clock::now();
  auto next_host_tick = last_state;
  while (!stopping_.load(std::memory_order_acquire)) {
    if (disconnected_.load(std::memory_order_relaxed)) {
      next_host_tick += period;
      std::this_thread::sleep_until(next_host_tick);
      device_time_us_ += std::chrono::duration_cast<std::chrono::microseconds>(period).count();
      tick_(tick_context_, std::chrono::microseconds(device_time_us_));
      continue;
    }
    // Wait in slices, so that stopClock is prompt whatever the timeout.
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(last_state + watchdog - Clock::now());
    std::uint8_t buffer[256];
    std::size_t n = 0;
    const auto wait = port_.read(static_cast<int>(std::clamp<std::int64_t>(left.count(), 0, 10)), buffer, sizeof buffer, n);
    if (stopping_.load(std::memory_order_acquire)) break;
    if (wait == SerialPort::Wait::kClosed) {
      device_time_us_ += std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - last_state).count();
      disconnect(kPortClosed);
      next_host_tick = Clock::now();
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const hpen_event event = hpen_parser_feed(&parser_, buffer[i]);
      if (event == HPEN_BAD_CRC || event == HPEN_BAD_LENGTH) bump(malformed_);
      if (event == HPEN_WRONG_VERSION) bump(wrong_version_);
      if (event != HPEN_FRAME) continue;
      if (hpen_parser_type(&parser_) != HPEN_STATE) continue;  // a late IDENTITY: nothing to do
      hpen_state s{};
      hpen_decode_state(hpen_parser_payload(&parser_), &s);
      if (have_state_ && static_cast<std::int16_t>(s.seq - last_seq_) <= 0) {
        bump(out_of_sequence_);
        continue;
      }
      last_state = Clock::now();
      takeState(s);
      tick_(tick_context_, std::chrono::microseconds(device_time_us_));
    }
    if (Clock::now() - last_state >= watchdog) {
      device_time_us_ += std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - last_state).count();
      disconnect(kNoState);
      next_host_tick = Clock::now();
    }
  }
}

void SerialDevice::Impl::disconnect(int reason) noexcept {
  fault_.store(reason, std::memory_order_release);
  disconnected_.store(true, std::memory_order_release);
  tick_(tick_context_, std::chrono::microseconds(device_time_us_));
}

// A STATE: the device's time unwrapped, the pen in W, its velocity filtered, the press.
void SerialDevice::Impl::takeState(const hpen_state& s) noexcept {
  bump(states_);
  if (have_state_ && static_cast<std::uint16_t>(s.seq - last_seq_) > 1u) {
    lost_states_.fetch_add(static_cast<std::uint16_t>(s.seq - last_seq_) - 1u, std::memory_order_relaxed);
  }
  const double dt = have_first_ ? static_cast<std::uint32_t>(s.time_us - last_time_us_) * 1e-6 : 0.0;
  if (have_first_) device_time_us_ += static_cast<std::uint32_t>(s.time_us - last_time_us_);
  else device_time_us_ = 0;
  have_first_ = true;
  last_time_us_ = s.time_us;
  last_seq_ = s.seq;

  q_ = jointAngles(spec_, s.count0, s.count1);
  Vec3 p_WT;
  impossible_pose_ = !penPosition(spec_, q_, p_WT);
  const double press_N = sensorForce_N(spec_, s.sensor);
  if (!impossible_pose_) {
    p_WT.z() = planarTipHeight(press_N, params_.contact_N);
    if (have_state_ && dt > 0.0) {
      const double alpha = dt / (dt + 1.0 / (2.0 * std::numbers::pi * params_.velocity_cutoff_hz));
      pen_.v_WT += alpha * ((p_WT - pen_.p_WT) / dt - pen_.v_WT);
      pen_.v_WT.z() = 0.0;
    } else {
      pen_.v_WT.setZero();
    }
    pen_.p_WT = p_WT;
  }
  pen_.t_s = static_cast<double>(device_time_us_) * 1e-6;
  pen_.buttons = (s.flags & HPEN_STATE_BUTTON) != 0 ? 1u : 0u;
  pen_.has_pressure = true;
  pen_.pressure_raw = press_N;
  have_state_ = true;

  const std::uint32_t counts[5] = {s.rx_malformed, s.rx_out_of_sequence, s.rx_wrong_version, s.watchdog_trips, s.tx_skipped};
  for (int i = 0; i < 5; ++i) device_counts_[i].store(counts[i], std::memory_order_relaxed);
}

DeviceStatus SerialDevice::Impl::read(std::chrono::nanoseconds now, PenState& out) noexcept {
  if (disconnected_.load(std::memory_order_acquire) || !have_state_) return DeviceStatus::kDisconnected;
  if (impossible_pose_) {
    fault_.store(kImpossiblePose, std::memory_order_release);
    return DeviceStatus::kFault;
  }
  out = pen_;
  out.t_s = std::chrono::duration<double>(now).count();
  return DeviceStatus::kOk;
}

DeviceStatus SerialDevice::Impl::write(const Vec3& f_on_pen_W) noexcept {
  if (disconnected_.load(std::memory_order_acquire) || !have_state_) return DeviceStatus::kDisconnected;
  const Vec3 f = f_on_pen_W.allFinite() ? f_on_pen_W : Vec3::Zero();
  const auto efforts = motorEfforts(spec_, jointTorques(spec_, q_, f));
  const hpen_command command{.seq = last_seq_, .effort0 = efforts[0], .effort1 = efforts[1], .flags = HPEN_COMMAND_ENABLE};
  std::uint8_t payload[HPEN_COMMAND_BYTES];
  hpen_encode_command(payload, &command);
  std::uint8_t frame[HPEN_MAX_FRAME_BYTES];
  const std::uint8_t length = hpen_frame(frame, HPEN_PROTOCOL_VERSION, HPEN_COMMAND, payload, HPEN_COMMAND_BYTES);
  last_efforts_.store(static_cast<std::int32_t>((static_cast<std::uint32_t>(static_cast<std::uint16_t>(efforts[0])) << 16) |
                                                static_cast<std::uint16_t>(efforts[1])),
                      std::memory_order_relaxed);
  if (!port_.write(frame, length)) bump(unsent_);
  return DeviceStatus::kOk;
}

std::string SerialDevice::Impl::faultReason() const {
  switch (fault_.load(std::memory_order_acquire)) {
    case kPortClosed: return fmt::format("{}: the port closed (the cable unplugged, or the pen reset)", uri_);
    case kNoState:
      return fmt::format("{}: no STATE from the pen for {} ms: the link is lost", uri_,
                         std::lround(stateTimeout_s() * 1e3));
    case kImpossiblePose:
      return fmt::format("{}: the encoders read a pose the linkage cannot take: home the pen again", uri_);
    default: return {};
  }
}

SerialCounters SerialDevice::Impl::counters() const noexcept {
  const auto load = [](const std::atomic<std::uint64_t>& c) { return c.load(std::memory_order_relaxed); };
  const auto device = [this](int i) { return device_counts_[i].load(std::memory_order_relaxed); };
  return {.states = load(states_),
          .malformed = load(malformed_),
          .out_of_sequence = load(out_of_sequence_),
          .wrong_version = load(wrong_version_),
          .lost_states = load(lost_states_),
          .unsent_commands = load(unsent_),
          .device_malformed = device(0),
          .device_out_of_sequence = device(1),
          .device_wrong_version = device(2),
          .device_watchdog_trips = device(3),
          .device_skipped_states = device(4)};
}

// ---- the Device interface ----

SerialDevice::SerialDevice(const SerialDeviceParams& params, std::string uri_text)
    : impl_(std::make_unique<Impl>(params, std::move(uri_text))) {}
SerialDevice::~SerialDevice() = default;
DeviceStatus SerialDevice::read(std::chrono::nanoseconds now, PenState& out) noexcept { return impl_->read(now, out); }
DeviceStatus SerialDevice::write(const Vec3& f_on_pen_W) noexcept { return impl_->write(f_on_pen_W); }
const DeviceLimits& SerialDevice::limits() const noexcept { return impl_->limits_; }
const std::string& SerialDevice::uri() const noexcept { return impl_->uri_; }
void SerialDevice::startClock(DeviceTickFn tick, void* context) { impl_->startClock(tick, context); }
void SerialDevice::stopClock() noexcept { impl_->stopClock(); }
std::string SerialDevice::faultReason() const { return impl_->faultReason(); }
const PlanarPenSpec& SerialDevice::spec() const noexcept { return impl_->spec_; }
bool SerialDevice::pausableClock() const noexcept { return impl_->params_.lockstep; }
SerialCounters SerialDevice::counters() const noexcept { return impl_->counters(); }
std::pair<std::int16_t, std::int16_t> SerialDevice::lastEfforts() const noexcept {
  const auto packed = static_cast<std::uint32_t>(impl_->last_efforts_.load(std::memory_order_relaxed));
  return {static_cast<std::int16_t>(packed >> 16), static_cast<std::int16_t>(packed & 0xFFFFu)};
}

std::unique_ptr<Device> openSerialDevice(const DeviceUri& uri, std::string_view uri_text) {
  return std::make_unique<SerialDevice>(serialDeviceParams(uri), std::string(uri_text));
}

std::string serialDeviceHelp() {
  return "serial://PORT keys (the open pen, docs/hardware.md):\n"
         "  baud                     the port's baud, default 1000000\n"
         "  home                     once: zero the encoders when the loop first starts after the pen's power-up (the "
         "linkage resting at its home pose), always: at every start, never; default once\n"
         "  timeout_s                how long opening waits for the pen's IDENTITY [s], default 3\n"
         "  velocity_hz              cut-off of the velocity filter [Hz], default 100\n"
         "  contact_N                a press below this is the pen lifted [N], default 0.05\n"
         "  state_timeout_s          the link is lost after this long without a STATE [s], default the pen's watchdog "
         "time (20 ms), or 60 s with lockstep=1\n"
         "  lockstep                 1: the pen is hattr-pen-emulator in lockstep, whose clock is simulated and pauses: "
         "judged by its own time, not the wall clock (never for a real pen); default 0\n"
         "  max_force_N              lower the pen's declared forces to this [N]\n";
}

}  // namespace hattr::device
