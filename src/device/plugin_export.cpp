#include "hattr/device/plugin_export.hpp"

#include <cmath>
#include <exception>
#include <string>

namespace hattr::device::plugin {
namespace {

/// The one plugin this shared object exports.
struct Exported {
  hattr_plugin table{};
  OpenFn open = nullptr;
};
Exported& exported() {
  static Exported e;
  return e;
}

/// Strings handed across the line live here until the same thread's next call.
thread_local std::string t_error_text;
std::string g_open_error;  // last failed open (main thread)

/// The host's simulated hand behind the HandScript interface.
class HostHand final : public HandScript {
 public:
  explicit HostHand(const hattr_host& host) : host_(host) {}
  HandCommand command(double t_s) noexcept override {
    hattr_hand_command c{};
    if (host_.hand_command(host_.context, t_s, &c) == 0) return HandCommand{};
    return HandCommand{.p_target_W = Vec3(c.p_target_m.x, c.p_target_m.y, c.p_target_m.z),
                       .v_target_W = Vec3(c.v_target_m_per_s.x, c.v_target_m_per_s.y, c.v_target_m_per_s.z),
                       .press_N = c.press_N,
                       .azimuth_rad = c.azimuth_rad,
                       .altitude_rad = c.altitude_rad,
                       .pen_down = c.pen_down != 0};
  }

 private:
  hattr_host host_;
};

/// One open device: the hand first, so it outlives the device that holds a pointer to it.
struct Handle {
  std::unique_ptr<HostHand> hand;
  std::unique_ptr<Device> device;
  hattr_tick_fn host_tick = nullptr;  // the host's tick while the device clock runs
  void* host_tick_context = nullptr;
};
Handle* handleOf(void* device) { return static_cast<Handle*>(device); }

std::int32_t statusCode(DeviceStatus status) noexcept {
  switch (status) {
    case DeviceStatus::kOk: return HATTR_PLUGIN_OK;
    case DeviceStatus::kDisconnected: return HATTR_PLUGIN_DISCONNECTED;
    case DeviceStatus::kFault: break;
  }
  return HATTR_PLUGIN_FAULT;
}

hattr_vec3 toC(const Vec3& v) noexcept { return {v.x(), v.y(), v.z()}; }

void* openDevice(const hattr_param* params, std::size_t count, const hattr_host* host) {
  try {
    DeviceUri uri{.scheme = "plugin", .target = exported().table.name, .query = {}};
    for (std::size_t i = 0; i < count; ++i) uri.query.emplace(params[i].key, params[i].value);
    auto handle = std::make_unique<Handle>();
    // Only a host of this ABI or newer offers the hand field.
    if (host && host->struct_size >= sizeof(hattr_host) && host->hand_command) handle->hand = std::make_unique<HostHand>(*host);
    handle->device = exported().open(uri, handle->hand.get());
    g_open_error.clear();
    return handle.release();
  } catch (const std::exception& e) {
    g_open_error = e.what();
  } catch (...) {
    g_open_error = "unknown error while opening the device";
  }
  return nullptr;
}

void closeDevice(void* device) {
  if (device == nullptr) return;
  Handle* handle = handleOf(device);
  handle->device->stopClock();
  (void)handle->device->write(Vec3::Zero());
  delete handle;
}

std::int32_t getLimits(void* device, hattr_device_limits* out) {
  const DeviceLimits& l = handleOf(device)->device->limits();
  *out = hattr_device_limits{l.degrees_of_freedom, toC(l.workspace_min_m), toC(l.workspace_max_m), l.peak_force_N,
                             l.continuous_force_N, l.max_stiffness_N_per_m, l.max_damping_N_s_per_m, l.nominal_rate_hz,
                             l.mass_kg, l.damping_N_s_per_m};
  return HATTR_PLUGIN_OK;
}

std::int32_t getInfo(void* device, hattr_device_info* out) {
  const Device& d = *handleOf(device)->device;
  const DeviceCapabilities caps = d.capabilities();
  std::int32_t clocking = HATTR_CLOCK_HOST;
  if (d.clocking() == DeviceClocking::kSimulatable) clocking = HATTR_CLOCK_SIMULATABLE;
  if (d.clocking() == DeviceClocking::kDeviceClock) clocking = HATTR_CLOCK_DEVICE;
  *out = hattr_device_info{clocking, caps.force_sensor, caps.pressure, caps.tilt};
  return HATTR_PLUGIN_OK;
}

std::int32_t readState(void* device, std::int64_t now_ns, hattr_pen_state* out) {
  PenState s;
  const DeviceStatus status = handleOf(device)->device->read(std::chrono::nanoseconds(now_ns), s);
  *out = hattr_pen_state{s.t_s,        toC(s.p_WT),  toC(s.v_WT),     s.buttons,     s.has_force,
                         toC(s.f_measured_W), s.has_pressure, s.pressure_raw, s.has_tilt, s.azimuth_rad,
                         s.altitude_rad};
  return statusCode(status);
}

std::int32_t writeForce(void* device, const hattr_vec3* force) {
  return statusCode(handleOf(device)->device->write(Vec3(force->x, force->y, force->z)));
}

/// The device's clock calls this; it calls the host's C tick.
void tickHost(void* context, std::chrono::nanoseconds now) noexcept {
  const Handle* handle = static_cast<const Handle*>(context);
  handle->host_tick(handle->host_tick_context, now.count());
}

std::int32_t startClock(void* device, hattr_tick_fn tick, void* context) {
  try {
    Handle* handle = handleOf(device);
    handle->host_tick = tick;
    handle->host_tick_context = context;
    handle->device->startClock(&tickHost, handle);
    return HATTR_PLUGIN_OK;
  } catch (const std::exception& e) {
    t_error_text = e.what();
  }
  return HATTR_PLUGIN_FAULT;
}

void stopClock(void* device) { handleOf(device)->device->stopClock(); }

const char* lastError(void* device) {
  if (device == nullptr) return g_open_error.c_str();
  try {
    t_error_text = handleOf(device)->device->faultReason();
  } catch (...) {
    t_error_text = "(no description)";
  }
  return t_error_text.c_str();
}

}  // namespace

const hattr_plugin* exportTable(const char* name, const char* description, OpenFn open,
                                std::uint32_t host_abi_version) noexcept {
  if (host_abi_version != HATTR_PLUGIN_ABI_VERSION) return nullptr;
  Exported& e = exported();
  e.open = open;
  e.table = hattr_plugin{HATTR_PLUGIN_ABI_VERSION, sizeof(hattr_plugin), name, description, &openDevice, &closeDevice,
                         &getLimits, &getInfo, &readState, &writeForce, &startClock, &stopClock, &lastError};
  return &e.table;
}

}  // namespace hattr::device::plugin
