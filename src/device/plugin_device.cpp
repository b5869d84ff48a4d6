#include "hattr/device/plugin_device.hpp"

#include <dlfcn.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <vector>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/install_layout.hpp"
#include "hattr/device/plugin_abi.h"

namespace hattr::device {
namespace {

/// A loaded shared object and its plugin table; dlclose on destruction.
class PluginLibrary {
 public:
  explicit PluginLibrary(const std::string& path) : path_(path) {
    // File first, so "missing" and "not a shared object" read differently.
    std::error_code ec;
    HATTR_THROW_UNLESS(std::filesystem::is_regular_file(path, ec),
                       "plugin:{}: file not found (expected the path of a hattr driver plugin, a .so file)", path);
    handle_ = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle_ == nullptr) {
      const char* why = dlerror();
      throw InputError(fmt::format("plugin:{}: not a loadable shared object: {}", path, why ? why : "dlopen failed"));
    }
    // The one entry symbol, then the table's version and size before anything else in it.
    void* entry = dlsym(handle_, HATTR_PLUGIN_ENTRY_SYMBOL);
    if (entry == nullptr) {
      dlclose(handle_);
      throw InputError(fmt::format("plugin:{}: no entry symbol \"{}\": not a hattr driver plugin", path,
                                   HATTR_PLUGIN_ENTRY_SYMBOL));
    }
    hattr_plugin_entry_fn entry_fn = nullptr;
    static_assert(sizeof(entry_fn) == sizeof(entry));
    std::memcpy(&entry_fn, &entry, sizeof(entry));
    table_ = entry_fn(HATTR_PLUGIN_ABI_VERSION);
    if (table_ == nullptr || table_->abi_version != HATTR_PLUGIN_ABI_VERSION ||
        table_->struct_size < sizeof(hattr_plugin)) {
      const std::string theirs =
          table_ == nullptr ? "none it would serve" : fmt::format("version {}", table_->abi_version);
      dlclose(handle_);
      throw InputError(fmt::format("plugin:{}: plugin ABI mismatch: the plugin speaks {}, this hattr speaks version {}",
                                   path, theirs, HATTR_PLUGIN_ABI_VERSION));
    }
    if (!(table_->open && table_->close && table_->get_limits && table_->get_info && table_->read_state &&
          table_->write_force && table_->last_error)) {
      dlclose(handle_);
      throw InputError(fmt::format("plugin:{}: its table lacks a required function (open, close, get_limits, get_info, "
                                   "read_state, write_force, last_error)",
                                   path));
    }
  }
  ~PluginLibrary() {
    if (handle_) dlclose(handle_);
  }
  PluginLibrary(const PluginLibrary&) = delete;
  PluginLibrary& operator=(const PluginLibrary&) = delete;

  [[nodiscard]] const hattr_plugin& table() const noexcept { return *table_; }
  [[nodiscard]] const std::string& path() const noexcept { return path_; }

 private:
  std::string path_;
  void* handle_ = nullptr;
  const hattr_plugin* table_ = nullptr;
};

Vec3 toVec3(const hattr_vec3& v) noexcept { return {v.x, v.y, v.z}; }
hattr_vec3 toC(const Vec3& v) noexcept { return {v.x(), v.y(), v.z()}; }

std::string_view statusText(std::int32_t status) noexcept {
  switch (status) {
    case HATTR_PLUGIN_FAULT: return "fault";
    case HATTR_PLUGIN_DISCONNECTED: return "disconnected";
    case HATTR_PLUGIN_TIMEOUT: return "timed out";
    default: return "unknown status";
  }
}

/// Why read() or write() last failed (servo thread writes, any thread reads).
enum class PluginFault : int { kNone, kReadStatus, kWriteStatus, kNonFiniteState };

class PluginDevice final : public Device {
 public:
  PluginDevice(std::shared_ptr<PluginLibrary> library, const DeviceUri& uri, std::string uri_text, HandScript* hand)
      : library_(std::move(library)), plugin_(library_->table()), uri_(std::move(uri_text)), hand_(hand) {
    // The host's offer: the simulated hand, if there is one.
    host_ = hattr_host{HATTR_PLUGIN_ABI_VERSION, sizeof(hattr_host), this, hand_ ? &PluginDevice::handCallback : nullptr};
    std::vector<hattr_param> params;
    params.reserve(uri.query.size());
    for (const auto& [key, value] : uri.query) params.push_back({key.c_str(), value.c_str()});
    device_ = plugin_.open(params.data(), params.size(), &host_);
    if (device_ == nullptr) {
      throw InputError(fmt::format("plugin:{}: the plugin could not open the device: {}", library_->path(),
                                   plugin_.last_error(nullptr)));
    }
    if (hand_) hand_->rewind();  // the plugin may have asked the hand where to start
    try {
      readDescription();
    } catch (...) {
      plugin_.close(device_);  // never leave an opened device behind (nor unload its code under it)
      throw;
    }
  }
  ~PluginDevice() override { plugin_.close(device_); }

  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override {
    hattr_pen_state s{};
    const std::int32_t status = plugin_.read_state(device_, now.count(), &s);
    if (status != HATTR_PLUGIN_OK) return fail(PluginFault::kReadStatus, status);
    // A state the loop could act on must be finite everywhere.
    if (!(std::isfinite(s.t_s) && toVec3(s.p_m).allFinite() && toVec3(s.v_m_per_s).allFinite() &&
          toVec3(s.f_measured_N).allFinite() && std::isfinite(s.pressure_raw) && std::isfinite(s.azimuth_rad) &&
          std::isfinite(s.altitude_rad))) {
      return fail(PluginFault::kNonFiniteState, HATTR_PLUGIN_FAULT);
    }
    out.t_s = std::chrono::duration<double>(now).count();
    out.p_WT = toVec3(s.p_m);
    out.v_WT = toVec3(s.v_m_per_s);
    out.buttons = s.buttons;
    out.has_force = s.has_force != 0;
    out.f_measured_W = toVec3(s.f_measured_N);
    out.has_pressure = s.has_pressure != 0;
    out.pressure_raw = s.pressure_raw;
    out.has_tilt = s.has_tilt != 0;
    out.azimuth_rad = s.azimuth_rad;
    out.altitude_rad = s.altitude_rad;
    return DeviceStatus::kOk;
  }

  DeviceStatus write(const Vec3& f_on_pen_W) noexcept override {
    const hattr_vec3 force = toC(f_on_pen_W);
    const std::int32_t status = plugin_.write_force(device_, &force);
    return status == HATTR_PLUGIN_OK ? DeviceStatus::kOk : fail(PluginFault::kWriteStatus, status);
  }

  const DeviceLimits& limits() const noexcept override { return limits_; }
  DeviceCapabilities capabilities() const noexcept override { return capabilities_; }
  const std::string& uri() const noexcept override { return uri_; }
  DeviceClocking clocking() const noexcept override { return clocking_; }

  void startClock(DeviceTickFn tick, void* context) override {
    HATTR_DEMAND(clocking_ == DeviceClocking::kDeviceClock && plugin_.start_clock, "startClock on {}", uri_);
    tick_ = tick;
    tick_context_ = context;
    const std::int32_t status = plugin_.start_clock(device_, &PluginDevice::tickTrampoline, this);
    if (status != HATTR_PLUGIN_OK) {
      throw Error(fmt::format("plugin:{}: the device clock did not start ({}): {}", library_->path(),
                              statusText(status), plugin_.last_error(device_)));
    }
  }
  void stopClock() noexcept override {
    if (plugin_.stop_clock) plugin_.stop_clock(device_);
  }

  // The plugin's own words when it has them, else what the host saw.
  std::string faultReason() const override {
    const auto fault = static_cast<PluginFault>(fault_.load(std::memory_order_acquire));
    if (fault == PluginFault::kNone) return {};
    if (fault == PluginFault::kNonFiniteState) return fmt::format("{}: the plugin returned a non-finite pen state", uri_);
    const std::string plugin_says = plugin_.last_error(device_);
    if (!plugin_says.empty()) return fmt::format("{}: {}", uri_, plugin_says);
    return fmt::format("{}: {} the device: {}", uri_, fault == PluginFault::kReadStatus ? "reading" : "writing the force to",
                       statusText(fault_status_.load(std::memory_order_acquire)));
  }

 private:
  // Limits and capabilities, checked once: a plugin's numbers are input like any other.
  void readDescription() {
    hattr_device_limits l{};
    hattr_device_info info{};
    HATTR_THROW_UNLESS(plugin_.get_limits(device_, &l) == HATTR_PLUGIN_OK && plugin_.get_info(device_, &info) == HATTR_PLUGIN_OK,
                       "plugin:{}: could not read the device's limits: {}", library_->path(), plugin_.last_error(device_));
    const Vec3 lo = toVec3(l.workspace_min_m);
    const Vec3 hi = toVec3(l.workspace_max_m);
    limits_ = DeviceLimits{.degrees_of_freedom = l.degrees_of_freedom,
                           .workspace_min_m = lo,
                           .workspace_max_m = hi,
                           .peak_force_N = l.peak_force_N,
                           .continuous_force_N = l.continuous_force_N,
                           .max_stiffness_N_per_m = l.max_stiffness_N_per_m,
                           .max_damping_N_s_per_m = l.max_damping_N_s_per_m,
                           .nominal_rate_hz = l.nominal_rate_hz,
                           .mass_kg = l.mass_kg,
                           .damping_N_s_per_m = l.damping_N_s_per_m};
    checkReportedLimits(limits_, fmt::format("plugin:{}: the device", library_->path()));
    capabilities_ = {.force_sensor = info.force_sensor != 0, .pressure = info.pressure != 0, .tilt = info.tilt != 0};
    switch (info.clocking) {
      case HATTR_CLOCK_HOST: clocking_ = DeviceClocking::kHostRealTime; break;
      case HATTR_CLOCK_SIMULATABLE: clocking_ = DeviceClocking::kSimulatable; break;
      case HATTR_CLOCK_DEVICE:
        HATTR_THROW_UNLESS(plugin_.start_clock && plugin_.stop_clock,
                           "plugin:{}: declares a device clock but has no start_clock/stop_clock", library_->path());
        clocking_ = DeviceClocking::kDeviceClock;
        break;
      default:
        throw InputError(fmt::format("plugin:{}: unknown clocking {} (expected 0 host, 1 simulatable, 2 device)",
                                     library_->path(), info.clocking));
    }
  }

  DeviceStatus fail(PluginFault fault, std::int32_t status) noexcept {
    fault_status_.store(status, std::memory_order_release);
    fault_.store(static_cast<int>(fault), std::memory_order_release);
    return status == HATTR_PLUGIN_DISCONNECTED ? DeviceStatus::kDisconnected : DeviceStatus::kFault;
  }

  static std::int32_t handCallback(void* context, double t_s, hattr_hand_command* out) {
    const HandCommand c = static_cast<PluginDevice*>(context)->hand_->command(t_s);
    *out = hattr_hand_command{toC(c.p_target_W), toC(c.v_target_W), c.press_N, c.azimuth_rad, c.altitude_rad,
                              c.pen_down ? 1 : 0};
    return 1;
  }
  static void tickTrampoline(void* context, std::int64_t now_ns) {
    auto* self = static_cast<PluginDevice*>(context);
    self->tick_(self->tick_context_, std::chrono::nanoseconds(now_ns));
  }

  std::shared_ptr<PluginLibrary> library_;
  const hattr_plugin& plugin_;
  std::string uri_;
  HandScript* hand_;
  hattr_host host_{};
  void* device_ = nullptr;
  DeviceLimits limits_;
  DeviceCapabilities capabilities_;
  DeviceClocking clocking_ = DeviceClocking::kHostRealTime;
  DeviceTickFn tick_ = nullptr;
  void* tick_context_ = nullptr;
  std::atomic<int> fault_{0};
  std::atomic<std::int32_t> fault_status_{0};
};

}  // namespace

std::vector<std::string> pluginSearchPath() {
  std::vector<std::string> folders;
  if (const char* env = std::getenv("HATTR_PLUGIN_PATH")) {
    std::string_view rest = env;
    while (!rest.empty()) {
      const auto colon = rest.find(':');
      if (colon != 0) folders.emplace_back(rest.substr(0, colon));
      rest = colon == std::string_view::npos ? std::string_view{} : rest.substr(colon + 1);
    }
  }
  // Then the plugin folder of the prefix this program is in (installed, or the build folder).
  if (const auto installed = findPluginDir()) folders.push_back(installed->string());
  return folders;
}

std::string resolvePlugin(const std::string& target) {
  if (target.find('/') != std::string::npos) return target;
  const std::string file = "libhattr_" + target + "_plugin.so";
  std::string searched;
  for (const auto& folder : pluginSearchPath()) {
    const auto candidate = std::filesystem::path(folder) / file;
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec)) return candidate.string();
    searched += (searched.empty() ? "" : ", ") + folder;
  }
  throw InputError(fmt::format("plugin:{}: no {} in the plugin search path ({}); give a path "
                               "(plugin:/path/to/lib.so) or add its folder to HATTR_PLUGIN_PATH",
                               target, file, searched.empty() ? "empty" : searched));
}

std::vector<PluginInfo> findPlugins() {
  std::vector<PluginInfo> found;
  for (const auto& folder : pluginSearchPath()) {
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
      const std::string name = entry.path().filename().string();
      if (!name.starts_with("libhattr_") || !name.ends_with("_plugin.so")) continue;
      try {
        found.push_back(inspectPlugin(entry.path().string()));
      } catch (const InputError&) {
        // Not a plugin this hattr can load: `hattr devices check` on it says why.
      }
    }
  }
  return found;
}

PluginInfo inspectPlugin(const std::string& path) {
  const PluginLibrary library(path);
  const hattr_plugin& t = library.table();
  return {path, t.name ? t.name : "", t.description ? t.description : "", t.abi_version};
}

std::unique_ptr<Device> openPluginDevice(const DeviceUri& uri, std::string_view uri_text, HandScript* hand) {
  HATTR_THROW_UNLESS(!uri.target.empty(), "device URI \"{}\": expected plugin:/path/to/plugin.so[?key=value&...]",
                     uri_text);
  auto library = std::make_shared<PluginLibrary>(resolvePlugin(uri.target));
  return std::make_unique<PluginDevice>(std::move(library), uri, std::string(uri_text), hand);
}

}  // namespace hattr::device
