// The simulated pen behind the driver ABI: `plugin:/path/libhattr_sim_plugin.so?key=value`.
// Takes the keys of sim://pen (see `hattr devices`) plus clock=host|device and rate_hz, and the
// host's simulated hand. With clock=host (the default) it may run in simulated time and a
// trial through it is bit-identical to the same trial on sim://pen; with clock=device it runs
// its own 1 kHz thread that calls the host's tick, as vendor schedulers do.

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/device/plugin_export.hpp"
#include "hattr/device/simulated_device.hpp"
#include "common/clock_thread.hpp"

namespace {

using namespace hattr;
using namespace hattr::device;

/// The pen starts at least this high above the hand's first target (as runTrial's).
constexpr double kLiftHeight_m = 0.003;

/// The simulated pen, with an optional clock of its own.
class SimPluginDevice final : public Device {
 public:
  SimPluginDevice(const SimulatedPenParams& params, HandScript* hand, bool own_clock, double rate_hz)
      : pen_(params, hand, "plugin:sim"),
        own_clock_(own_clock),
        clock_(std::chrono::nanoseconds(std::llround(1e9 / rate_hz))) {}
  ~SimPluginDevice() override { stopClock(); }

  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override { return pen_.read(now, out); }
  DeviceStatus write(const Vec3& f) noexcept override { return pen_.write(f); }
  const DeviceLimits& limits() const noexcept override { return pen_.limits(); }
  DeviceCapabilities capabilities() const noexcept override { return pen_.capabilities(); }
  const std::string& uri() const noexcept override { return pen_.uri(); }
  DeviceClocking clocking() const noexcept override {
    return own_clock_ ? DeviceClocking::kDeviceClock : DeviceClocking::kSimulatable;
  }

  // The device's own thread at its rate; the force is zero when it stops.
  void startClock(DeviceTickFn tick, void* context) override {
    HATTR_DEMAND(own_clock_, "startClock on a plugin:sim without clock=device");
    clock_.start(tick, context, [this] { (void)pen_.write(Vec3::Zero()); });
  }
  void stopClock() noexcept override { clock_.stop(); }

 private:
  SimulatedDevice pen_;
  bool own_clock_;
  plugins::ClockThread clock_;
};

std::unique_ptr<Device> openSim(const DeviceUri& uri, HandScript* hand) {
  // The plugin's own keys, then the simulated pen's (whose parser names any unknown key).
  DeviceUri pen_uri{.scheme = "sim", .target = "pen", .query = uri.query};
  bool own_clock = false;
  double rate_hz = 1000.0;
  if (auto it = pen_uri.query.find("clock"); it != pen_uri.query.end()) {
    HATTR_THROW_UNLESS(it->second == "host" || it->second == "device",
                       "sim plugin: key clock: expected host or device, got \"{}\"", it->second);
    own_clock = it->second == "device";
    pen_uri.query.erase(it);
  }
  if (auto it = pen_uri.query.find("rate_hz"); it != pen_uri.query.end()) {
    char* end = nullptr;
    rate_hz = std::strtod(it->second.c_str(), &end);
    HATTR_THROW_UNLESS(end && *end == '\0' && std::isfinite(rate_hz) && rate_hz >= 100.0 && rate_hz <= 10000.0,
                       "sim plugin: key rate_hz: expected a number in [100, 10000], got \"{}\"", it->second);
    pen_uri.query.erase(it);
  }
  SimulatedPenParams params;
  try {
    params = simulatedPenParams(pen_uri);
  } catch (const InputError& e) {
    throw InputError(fmt::format("sim plugin (keys: clock, rate_hz and those of sim://pen): {}", e.what()));
  }
  params.limits.nominal_rate_hz = rate_hz;
  // Start where the hand starts, lifted, as a trial on sim://pen does.
  if (hand) {
    hand->rewind();
    params.start_position_W = hand->command(0.0).p_target_W;
    params.start_position_W.z() = std::max(params.start_position_W.z(), kLiftHeight_m);
    hand->rewind();
  }
  return std::make_unique<SimPluginDevice>(params, hand, own_clock, rate_hz);
}

}  // namespace

HATTR_EXPORT_DEVICE_PLUGIN("sim", "the simulated pen (sim://pen) behind the plugin ABI", openSim)
