// A device that moves the pen along a recorded haptic profile and keeps the forces it was
// sent: `plugin:/path/libhattr_replay_plugin.so?profile=FILE[&forces=OUT.csv][&clock=device]`.
// For tests and demos without a pen: what hattr commands can be checked against what a
// recorded writer did. Keys:
//   profile=FILE     the profile to replay (required); position, velocity, pen-down, tilt, and
//                    the recorded user force as a force-sensor reading
//   forces=OUT.csv   at close, a haptic profile of the replayed positions with the force each
//                    write sent (f_cmd); refused if OUT.csv exists (nothing recorded is lost)
//   clock=host|device  host (default): the host's clock, simulated time included; device: a
//                    thread of its own calls the host's tick at rate_hz (like vendor schedulers)
//   rate_hz=R        the device clock's rate (default 1000)

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/device/plugin_export.hpp"
#include "hattr/io/profile_csv.hpp"
#include "common/clock_thread.hpp"

namespace {

using namespace hattr;
using namespace hattr::device;

class ReplayDevice final : public Device {
 public:
  ReplayDevice(HapticProfile profile, std::filesystem::path forces_out, bool own_clock, double rate_hz)
      : profile_(std::move(profile)),
        forces_out_(std::move(forces_out)),
        own_clock_(own_clock),
        clock_(std::chrono::nanoseconds(std::llround(1e9 / rate_hz))),
        uri_("plugin:replay") {
    limits_.nominal_rate_hz = rate_hz;
    // Room for every write of the profile's length plus a minute, so write() never allocates.
    const double span_s = profile_.duration_s() + 60.0;
    forces_.reserve(static_cast<std::size_t>(std::ceil(span_s * std::max(rate_hz, 1000.0))));
  }
  ~ReplayDevice() override {
    stopClock();
    if (!forces_out_.empty()) writeForces();
  }

  // The recorded sample at the time (linear interpolation; the cursor rewinds if time does).
  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override {
    const auto& s = profile_.samples();
    const double t = std::chrono::duration<double>(now).count() + s.front().t_s;
    if (cursor_ > 0 && s[cursor_].t_s > t) cursor_ = 0;
    while (cursor_ + 1 < s.size() && s[cursor_ + 1].t_s <= t) ++cursor_;
    const Sample& a = s[cursor_];
    const Sample& b = s[std::min(cursor_ + 1, s.size() - 1)];
    const double span = b.t_s - a.t_s;
    const double w = span > 0.0 ? std::clamp((t - a.t_s) / span, 0.0, 1.0) : 0.0;
    out.t_s = t - s.front().t_s;
    out.p_WT = (1.0 - w) * a.p_WT + w * b.p_WT;
    out.v_WT = t < s.back().t_s ? Vec3((1.0 - w) * a.v_WT + w * b.v_WT) : Vec3(Vec3::Zero());
    out.buttons = (w < 0.5 ? a.pen_down : b.pen_down) ? 1u : 0u;
    out.has_force = true;
    out.f_measured_W = (1.0 - w) * a.f_user_W + w * b.f_user_W;
    out.has_tilt = profile_.rawChannels().tilt;
    out.azimuth_rad = a.tilt_azimuth_rad;
    out.altitude_rad = a.tilt_altitude_rad;
    last_ = out;
    return DeviceStatus::kOk;
  }

  // Keeps the force with the pen it was meant for; counts what does not fit.
  DeviceStatus write(const Vec3& f) noexcept override {
    if (forces_.size() == forces_.capacity()) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return DeviceStatus::kOk;
    }
    Sample kept;
    kept.t_s = last_.t_s;
    kept.p_WT = last_.p_WT;
    kept.v_WT = last_.v_WT;
    kept.f_cmd_W = f;
    kept.pen_down = (last_.buttons & 1u) != 0;
    forces_.push_back(kept);
    return DeviceStatus::kOk;
  }

  const DeviceLimits& limits() const noexcept override { return limits_; }
  DeviceCapabilities capabilities() const noexcept override {
    return {.force_sensor = true, .tilt = profile_.rawChannels().tilt};
  }
  const std::string& uri() const noexcept override { return uri_; }
  DeviceClocking clocking() const noexcept override {
    return own_clock_ ? DeviceClocking::kDeviceClock : DeviceClocking::kSimulatable;
  }
  std::string faultReason() const override {
    const auto dropped = dropped_.load();
    return dropped ? fmt::format("{} forces did not fit the replay buffer and were not kept", dropped) : "";
  }

  void startClock(DeviceTickFn tick, void* context) override {
    HATTR_DEMAND(own_clock_, "startClock on a plugin:replay without clock=device");
    clock_.start(tick, context);
  }
  void stopClock() noexcept override { clock_.stop(); }

 private:
  // The kept forces as a haptic profile (positions as replayed, f_cmd as received).
  void writeForces() noexcept {
    try {
      ProfileMetadata meta = profile_.metadata();
      meta.source = fmt::format("replay plugin: forces sent while replaying {}", profile_.metadata().source);
      HapticProfile kept(meta);
      kept.reserve(forces_.size());
      // A profile's time only goes forward: a write in the same tick as the last, or after the
      // host restarted its clock, is not a new sample.
      std::uint64_t skipped = 0;
      for (const Sample& s : forces_) {
        if (kept.empty() || s.t_s > kept.samples().back().t_s) {
          kept.append(s);
        } else {
          ++skipped;
        }
      }
      kept.metadata().extra["forces_dropped"] = fmt::format("{}", dropped_.load());
      kept.metadata().extra["forces_not_after_previous"] = fmt::format("{}", skipped);
      if (!kept.empty()) io::writeProfileCsv(kept, forces_out_, hattr::Overwrite::kRefuse);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "replay plugin: could not write %s: %s\n", forces_out_.c_str(), e.what());
    }
  }

  HapticProfile profile_;
  std::filesystem::path forces_out_;
  bool own_clock_;
  plugins::ClockThread clock_;
  std::string uri_;
  DeviceLimits limits_;
  std::size_t cursor_ = 0;
  PenState last_;
  std::vector<Sample> forces_;
  std::atomic<std::uint64_t> dropped_{0};
};

std::unique_ptr<Device> openReplay(const DeviceUri& uri, HandScript* /*host_hand*/) {
  constexpr std::string_view kKeys[] = {"profile", "forces", "clock", "rate_hz"};
  for (const auto& [key, value] : uri.query) {
    HATTR_THROW_UNLESS(std::find(std::begin(kKeys), std::end(kKeys), key) != std::end(kKeys),
                       "replay plugin: unknown key \"{}\": expected one of profile, forces, clock, rate_hz", key);
  }
  const auto profile_it = uri.query.find("profile");
  HATTR_THROW_UNLESS(profile_it != uri.query.end(), "replay plugin: key profile=FILE is required (the profile to replay)");
  HapticProfile profile = io::readProfileCsv(profile_it->second);
  HATTR_THROW_UNLESS(!profile.empty(), "replay plugin: {}: the profile has no samples", profile_it->second);

  std::filesystem::path forces;
  if (auto it = uri.query.find("forces"); it != uri.query.end()) {
    forces = it->second;
    HATTR_THROW_UNLESS(!std::filesystem::exists(forces), "replay plugin: key forces: {} exists; choose another file "
                       "(a replay never replaces a recording)", it->second);
  }
  bool own_clock = false;
  if (auto it = uri.query.find("clock"); it != uri.query.end()) {
    HATTR_THROW_UNLESS(it->second == "host" || it->second == "device",
                       "replay plugin: key clock: expected host or device, got \"{}\"", it->second);
    own_clock = it->second == "device";
  }
  double rate_hz = 1000.0;
  if (auto it = uri.query.find("rate_hz"); it != uri.query.end()) {
    char* end = nullptr;
    rate_hz = std::strtod(it->second.c_str(), &end);
    HATTR_THROW_UNLESS(end && *end == '\0' && std::isfinite(rate_hz) && rate_hz >= 100.0 && rate_hz <= 10000.0,
                       "replay plugin: key rate_hz: expected a number in [100, 10000], got \"{}\"", it->second);
  }
  return std::make_unique<ReplayDevice>(std::move(profile), std::move(forces), own_clock, rate_hz);
}

}  // namespace

HATTR_EXPORT_DEVICE_PLUGIN("replay", "moves the pen along a recorded profile and keeps the forces it was sent",
                           openReplay)
