#include "hattr/servo/servo_loop.hpp"

#include <cmath>
#include <future>

#include "hattr/core/error.hpp"

namespace hattr::servo {
namespace {

std::chrono::nanoseconds periodFor(double rate_hz) {
  HATTR_THROW_UNLESS(std::isfinite(rate_hz) && rate_hz >= 1.0 && rate_hz <= 10'000.0,
                     "servo rate: expected 1 to 10000 Hz, got {}", rate_hz);
  return std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(1e9 / rate_hz)));
}

double seconds(std::chrono::nanoseconds ns) noexcept { return static_cast<double>(ns.count()) * 1e-9; }

void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

}  // namespace

std::string_view loopClockName(LoopClock clock) noexcept {
  switch (clock) {
    case LoopClock::kNone: return "none";
    case LoopClock::kSimulated: return "simulated";
    case LoopClock::kRealTime: return "real-time";
    case LoopClock::kDevice: return "device";
  }
  return "unknown";
}

ServoLoop::ServoLoop(device::Device& device, ServoConfig config)
    : device_(device),
      pausable_clock_(device.pausableClock()),
      config_(std::move(config)),
      period_(periodFor(config_.rate_hz)),
      safety_(config_.safety, device.limits()),
      samples_(config_.sample_ring_capacity),
      commands_(config_.command_ring_capacity) {
  HATTR_THROW_UNLESS(config_.stall_threshold > period_,
                     "servo stall threshold: expected more than one period ({} ns), got {} ns", period_.count(),
                     config_.stall_threshold.count());
}

ServoLoop::~ServoLoop() { stop(); }

void ServoLoop::drainCommands() noexcept {
  ServoCommand command;
  // Bounded: a flood of commands cannot stretch a tick.
  for (int i = 0; i < 8 && commands_.tryPop(command); ++i) {
    switch (command.type) {
      case ServoCommand::Type::kClearFault: safety_.clearFault(); break;
      case ServoCommand::Type::kRestartRamp: safety_.restartRamp(); break;
      case ServoCommand::Type::kSetGuidanceParameter:
        if (guidance_) (void)guidance_->setParameter(command.parameter, command.value);
        break;
    }
  }
}

bool ServoLoop::readPen(std::chrono::nanoseconds now, PenState& pen, TickStatus& status) noexcept {
  // A device fault latches; a lost link (or an unplugged device) zeroes the force while it
  // lasts and ramps in again when it returns.
  const device::DeviceStatus read_status = device_.read(now, pen);
  // A failed read holds the last good position, at rest, at this tick's time: a device need
  // not fill the state it could not read, and the tick's sample (zero command) must still
  // fall on the loop's clock, where the recording keeps it.
  if (read_status == device::DeviceStatus::kOk) {
    last_good_pen_ = pen;
  } else {
    pen = last_good_pen_;
    pen.t_s = seconds(now);
    pen.v_WT.setZero();
  }
  if (read_status == device::DeviceStatus::kFault) safety_.latchFault(SafetyFault::kDeviceError);
  const bool disconnected = read_status == device::DeviceStatus::kDisconnected;
  if (disconnected) {
    if (!link_down_) bump(counters_.link_faults);
    bump(counters_.disconnected_ticks);
    status = TickStatus::kDeviceError;
  }
  link_down_ = disconnected;
  counters_.disconnected.store(disconnected, std::memory_order_relaxed);
  return disconnected;
}

void ServoLoop::publish(const PenState& pen, const ContactForces& contact, const Vec3& command, const Vec3& guide) noexcept {
  Sample sample;
  sample.t_s = pen.t_s;
  sample.p_WT = pen.p_WT;
  sample.v_WT = pen.v_WT;
  sample.f_user_W = contact.f_on_paper_W;
  sample.f_cmd_W = command;
  sample.f_guide_W = guide;
  sample.in_contact = contact.in_contact;
  sample.pen_down = contact.in_contact;
  sample.pressure_raw = pen.has_pressure ? pen.pressure_raw : 0.0;
  sample.tilt_azimuth_rad = pen.azimuth_rad;
  sample.tilt_altitude_rad = pen.altitude_rad;
  if (!samples_.tryPush(TickSample{tick_number_, sample})) bump(counters_.dropped_samples);
  ++tick_number_;
  if (latest_due_) latest_.write(sample);

  // The count is published after the tick's sample is in the ring (release): whoever reads the
  // count (acquire) and ends a recording before that tick finds the sample in the ring. The
  // ticking thread is its only writer: a plain store, not a locked add.
  counters_.ticks.store(counters_.ticks.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  // A fault is published after its tick is counted and its sample is in the ring: whoever
  // sees the fault (acquire) and ends the recording at the tick count keeps the faulting tick.
  counters_.faults.store(safety_.faultCount(), std::memory_order_release);
}

TickStatus ServoLoop::tick(std::chrono::nanoseconds now) noexcept {
  // The tick's compute time, on a real clock only: simulated time runs as fast as it can, the
  // figure would say nothing, and reading the clock is a twentieth of a simulated tick.
  const bool timed = clock_.load(std::memory_order_relaxed) != LoopClock::kSimulated;
  const auto compute_start = timed ? monotonicNow() : std::chrono::nanoseconds{};
  TickStatus status = TickStatus::kRunning;

  // Measured period; a gap beyond the threshold is a stall: zero force, ramp in again.
  const std::chrono::nanoseconds dt = last_now_.count() < 0 ? period_ : now - last_now_;
  const bool stalled = last_now_.count() >= 0 && dt > config_.stall_threshold;
  if (stalled) {
    bump(counters_.stalls);
    status = TickStatus::kStalled;
  }
  last_now_ = now;
  const double dt_s = seconds(dt);
  drainCommands();

  // Read the pen, render the paper, add guidance.
  PenState pen;
  const bool disconnected = readPen(now, pen, status);
  ContactForces contact;
  if (world_) world_->render(pen, dt_s, contact);
  const Vec3 guide = guidance_ ? guidance_->compute(pen, contact, dt_s) : Vec3(Vec3::Zero());

  // A consumer the loop depends on has stopped taking samples.
  // (Not on a pausable device clock: its loop time runs ahead of the wall, and the ring holds it.)
  const bool consumer_stalled = consumer_time_s_ && !pausable_clock_ &&
                                pen.t_s - consumer_time_s_->load(std::memory_order_acquire) > seconds(config_.stall_threshold);
  if (consumer_stalled) bump(counters_.consumer_stalls);

  // Every force passes the safety path; a stall zeroes it outright.
  Vec3 command = Vec3::Zero();
  if (stalled || consumer_stalled || disconnected) {
    safety_.restartRamp();
  } else {
    command = safety_.filter(contact.f_on_pen_W, guide, pen.p_WT, dt_s);
  }
  const device::DeviceStatus write_status = device_.write(command);
  if (write_status == device::DeviceStatus::kFault) safety_.latchFault(SafetyFault::kDeviceError);
  if (safety_.fault() != SafetyFault::kNone) status = TickStatus::kFaulted;

  publish(pen, contact, command, guide);
  if (timed) tick_compute_.record((monotonicNow() - compute_start).count());
  return status;
}

void ServoLoop::runSimulated(std::size_t ticks) noexcept {
  clock_.store(LoopClock::kSimulated, std::memory_order_release);
  for (std::size_t i = 0; i < ticks; ++i) {
    latest_due_ = i + 1 == ticks;  // the newest sample for a display: the call's last
    (void)tick(sim_now_);
    sim_now_ += period_;
  }
  latest_due_ = true;
}

void ServoLoop::start() {
  HATTR_DEMAND(!running(), "start() on a running servo loop");
  stop_requested_.store(false);
  if (device_.clocking() == device::DeviceClocking::kDeviceClock) {
    startDeviceClock();
    return;
  }
  clock_.store(LoopClock::kRealTime, std::memory_order_release);
  std::promise<void> started;
  auto started_future = started.get_future();
  thread_ = std::thread([this, &started] {
    try {
      realtime_report_ = applyRealtime(config_.realtime);
    } catch (...) {
      started.set_exception(std::current_exception());
      return;
    }
    running_.store(true, std::memory_order_release);
    started.set_value();
    runRealtime();
  });
  try {
    started_future.get();
  } catch (...) {
    thread_.join();
    throw;
  }
}

void ServoLoop::stop() {
  stop_requested_.store(true, std::memory_order_release);
  // A device clock stops first (no tick runs after stopClock returns), then its watchdog.
  if (clock() == LoopClock::kDevice && running()) device_.stopClock();
  if (thread_.joinable()) thread_.join();
  running_.store(false, std::memory_order_release);
}

// The device calls the tick from its own thread; the loop measures the period between calls.
// Its rate is the device's: gains and passivity bounds were sized for the configured rate, so a
// device clock at another rate is refused.
void ServoLoop::startDeviceClock() {
  const double device_hz = device_.limits().nominal_rate_hz;
  HATTR_THROW_UNLESS(std::abs(device_hz - config_.rate_hz) <= 0.01 * device_hz,
                     "{}: the device's clock runs at {} Hz, the servo loop was set up for {} Hz: use --rate {}",
                     device_.uri(), device_hz, config_.rate_hz, device_hz);
  clock_.store(LoopClock::kDevice, std::memory_order_release);
  last_device_tick_ns_.store(monotonicNow().count(), std::memory_order_release);
  running_.store(true, std::memory_order_release);
  try {
    device_.startClock(&ServoLoop::deviceTick, this);
  } catch (...) {
    running_.store(false, std::memory_order_release);
    throw;
  }
  thread_ = std::thread([this] { watchDeviceClock(); });
}

void ServoLoop::deviceTick(void* context, std::chrono::nanoseconds now) noexcept {
  auto* self = static_cast<ServoLoop*>(context);
  // Stopping: the device's thread gets zero force until its clock has stopped.
  if (self->stop_requested_.load(std::memory_order_acquire)) {
    (void)self->device_.write(Vec3::Zero());
    return;
  }
  const auto wall = monotonicNow();
  if (self->last_device_wall_.count() >= 0) {
    self->period_error_.record(std::abs((wall - self->last_device_wall_ - self->period_).count()));
  }
  self->last_device_wall_ = wall;
  (void)self->tick(now);
  const auto done = monotonicNow();
  if (done - wall > self->period_) bump(self->counters_.overruns);
  self->last_device_tick_ns_.store(done.count(), std::memory_order_release);
}

// A device clock that stops calling cannot be made to tick: count the stall so the run is
// marked (the device zeroes its force on its own without commands, as the ABI requires).
void ServoLoop::watchDeviceClock() {
  bool stalled = false;
  while (!stop_requested_.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const auto gap = monotonicNow().count() - last_device_tick_ns_.load(std::memory_order_acquire);
    const bool now_stalled = gap > config_.stall_threshold.count() && !pausable_clock_;
    if (now_stalled && !stalled) bump(counters_.stalls);
    stalled = now_stalled;
  }
}

// Absolute deadlines on CLOCK_MONOTONIC; a late tick is counted, never made up for.
void ServoLoop::runRealtime() {
  const auto start = monotonicNow();
  auto deadline = start + period_;
  auto last_wake = start;
  bool first = true;
  while (!stop_requested_.load(std::memory_order_acquire)) {
    sleepUntil(deadline, config_.realtime.final_spin);
    const auto wake = monotonicNow();
    if (!first) period_error_.record(std::abs((wake - last_wake - period_).count()));
    first = false;
    last_wake = wake;
    (void)tick(wake - start);
    const auto done = monotonicNow();
    deadline += period_;
    if (done > deadline) {
      bump(counters_.overruns);
      deadline = done + period_;
    }
  }
  (void)device_.write(Vec3::Zero());
  running_.store(false, std::memory_order_release);
}

}  // namespace hattr::servo
