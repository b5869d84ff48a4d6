#include "hattr/device/vendor_adapter.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <thread>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::device {
namespace {

/// Why the device last failed (fault_kind_).
enum FaultKind : int { kNoFault, kReadError, kWriteError, kNonFiniteReading, kNonFiniteForce };

double parseNumber(const std::string& key, const std::string& text) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  HATTR_THROW_UNLESS(ec == std::errc{} && end == text.data() + text.size() && std::isfinite(value),
                     "vendor device: key {}: expected a number, got \"{}\"", key, text);
  return value;
}

Vec3 parseTriple(const std::string& key, const std::string& text) {
  Vec3 v;
  std::size_t start = 0;
  for (int i = 0; i < 3; ++i) {
    const std::size_t comma = text.find(',', start);
    HATTR_THROW_UNLESS((i < 2) == (comma != std::string::npos), "vendor device: key {}: expected x,y,z, got \"{}\"",
                       key, text);
    v[i] = parseNumber(key, text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    start = comma + 1;
  }
  return v;
}

// The workspace box of D, in W: the bounding box of its eight corners moved to W.
void workspaceInW(const VendorDescription& d, Vec3& lo_W, Vec3& hi_W) {
  lo_W = Vec3::Constant(std::numeric_limits<double>::infinity());
  hi_W = -lo_W;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 c_D((corner & 1) ? d.workspace_max_D.x() : d.workspace_min_D.x(),
                   (corner & 2) ? d.workspace_max_D.y() : d.workspace_min_D.y(),
                   (corner & 4) ? d.workspace_max_D.z() : d.workspace_min_D.z());
    const Vec3 c_W = d.R_WD * ((c_D - d.paper_origin_D) * d.length_unit_m);
    lo_W = lo_W.cwiseMin(c_W);
    hi_W = hi_W.cwiseMax(c_W);
  }
}

/// The device clock's time base (CLOCK_MONOTONIC on Linux, as the servo loop's).
std::chrono::nanoseconds monotonicNow() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch());
}

}  // namespace

void VendorBackend::startScheduler(void (*)(void*), void*) {
  throw Error("this vendor device has no scheduler of its own");
}

VendorDevice::VendorDevice(std::unique_ptr<VendorBackend> backend, const DeviceUri& uri)
    : backend_(std::move(backend)), uri_(fmt::format("plugin:{}", uri.target)) {
  // Split the URI's keys: the adapter's own, then the backend's; anything else is refused.
  std::map<std::string, std::string> backend_params;
  std::string max_force, paper_origin;
  const std::vector<std::string> backend_keys = backend_->keys();
  for (const auto& [key, value] : uri.query) {
    if (key == "max_force_N") {
      max_force = value;
    } else if (key == "paper_origin") {
      paper_origin = value;
    } else if (std::find(backend_keys.begin(), backend_keys.end(), key) != backend_keys.end()) {
      backend_params.emplace(key, value);
    } else {
      std::string accepted = "max_force_N, paper_origin";
      for (const auto& k : backend_keys) accepted += ", " + k;
      throw InputError(fmt::format("{}: unknown key \"{}\": expected one of {}", uri_, key, accepted));
    }
  }
  // The adapter's own values are checked before the SDK opens anything.
  const double cap = max_force.empty() ? 0.0 : parseNumber("max_force_N", max_force);
  const bool has_origin = !paper_origin.empty();
  const Vec3 origin = has_origin ? parseTriple("paper_origin", paper_origin) : Vec3(Vec3::Zero());
  description_ = backend_->open(backend_params);
  try {
    if (has_origin) description_.paper_origin_D = origin;
    describeInSi(cap, max_force);
  } catch (...) {
    backend_->close();  // an SDK device opened with force output is never left behind
    throw;
  }
  force_limit_N_ = limits_.peak_force_N;
}

// The SDK's numbers in SI and W, checked like any input; `cap` lowers the force limit (0: none).
void VendorDevice::describeInSi(double cap, const std::string& cap_text) {
  const VendorDescription& d = description_;
  const double unit = d.length_unit_m;
  HATTR_THROW_UNLESS(std::isfinite(unit) && unit > 0.0 && d.peak_force_N > 0.0 && d.continuous_force_N > 0.0 &&
                         d.max_stiffness_N_per_unit > 0.0 && d.nominal_rate_hz > 0.0,
                     "{} ({}): the SDK reported unusable limits: length unit {} m, peak {} N, continuous {} N, "
                     "stiffness {} N/unit, rate {} Hz",
                     uri_, d.model, unit, d.peak_force_N, d.continuous_force_N, d.max_stiffness_N_per_unit, d.nominal_rate_hz);
  limits_.degrees_of_freedom = 3;
  workspaceInW(d, limits_.workspace_min_m, limits_.workspace_max_m);
  limits_.continuous_force_N = std::min(d.continuous_force_N, d.peak_force_N);
  limits_.peak_force_N = d.peak_force_N;
  limits_.max_stiffness_N_per_m = d.max_stiffness_N_per_unit / unit;
  limits_.max_damping_N_s_per_m = d.max_damping_N_s_per_unit / unit;
  limits_.nominal_rate_hz = d.nominal_rate_hz;
  limits_.mass_kg = d.mass_kg;
  limits_.damping_N_s_per_m = d.damping_N_s_per_m;
  if (!cap_text.empty()) {
    HATTR_THROW_UNLESS(cap > 0.0 && cap <= d.peak_force_N,
                       "{}: key max_force_N: expected (0, {}] N (the device's peak force; it can only be lowered), got {}",
                       uri_, d.peak_force_N, cap_text);
    limits_.peak_force_N = std::min(limits_.peak_force_N, cap);
    limits_.continuous_force_N = std::min(limits_.continuous_force_N, cap);
  }
}

VendorDevice::~VendorDevice() {
  stopClock();
  backend_->close();
}

DeviceStatus VendorDevice::fail(int kind, int code) noexcept {
  fault_code_.store(code, std::memory_order_release);
  fault_kind_.store(kind, std::memory_order_release);
  return DeviceStatus::kFault;
}

// SDK units and frame to SI and W; a non-finite reading is a fault, never a state.
DeviceStatus VendorDevice::read(std::chrono::nanoseconds now, PenState& out) noexcept {
  VendorReading r;
  if (const int code = backend_->read(r); code != 0) return fail(kReadError, code);
  if (!r.position_D.allFinite() || !r.velocity_D.allFinite()) return fail(kNonFiniteReading, 0);
  const VendorDescription& d = description_;
  out.t_s = std::chrono::duration<double>(now).count();
  out.p_WT = d.R_WD * ((r.position_D - d.paper_origin_D) * d.length_unit_m);
  out.v_WT = d.R_WD * (r.velocity_D * d.length_unit_m);
  out.buttons = r.buttons;
  return DeviceStatus::kOk;
}

// W to D; clamped to the peak force as the last line of defence.
DeviceStatus VendorDevice::write(const Vec3& f_on_pen_W) noexcept {
  wrote_in_frame_ = true;
  if (!f_on_pen_W.allFinite()) {
    (void)backend_->write(Vec3::Zero());
    return fail(kNonFiniteForce, 0);
  }
  Vec3 f_W = f_on_pen_W;
  const double norm = f_W.norm();
  if (norm > force_limit_N_) f_W *= force_limit_N_ / norm;
  const int code = backend_->write(description_.R_WD.transpose() * f_W);
  return code == 0 ? DeviceStatus::kOk : fail(kWriteError, code);
}

// Inside the SDK's frame: the host's tick reads and writes; a frame it did not write gets zero,
// and so does every frame once stopping.
void VendorDevice::onFrame(void* context) noexcept {
  auto* self = static_cast<VendorDevice*>(context);
  if (self->stopping_.load(std::memory_order_acquire)) {
    (void)self->backend_->write(Vec3::Zero());
    self->frames_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  self->wrote_in_frame_ = false;
  self->tick_(self->tick_context_, monotonicNow() - self->clock_start_);
  if (!self->wrote_in_frame_) {
    (void)self->backend_->write(Vec3::Zero());
    self->unwritten_frames_.fetch_add(1, std::memory_order_relaxed);
  }
  self->frames_.fetch_add(1, std::memory_order_relaxed);
}

void VendorDevice::startClock(DeviceTickFn tick, void* context) {
  HATTR_DEMAND(description_.device_clock && !clock_running_, "startClock on {}", uri_);
  tick_ = tick;
  tick_context_ = context;
  clock_start_ = monotonicNow();
  stopping_.store(false, std::memory_order_release);
  try {
    backend_->startScheduler(&VendorDevice::onFrame, this);
  } catch (...) {
    backend_->stopScheduler();  // nothing of a half-started scheduler may call us later
    throw;
  }
  clock_running_ = true;
}

// Zero force in the SDK's own frames first (writes are valid only there), then stop it.
void VendorDevice::stopClock() noexcept {
  if (!clock_running_) return;
  stopping_.store(true, std::memory_order_release);
  const std::uint64_t seen = frames_.load();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(50);
  while (frames_.load() < seen + 2 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  backend_->stopScheduler();
  clock_running_ = false;
}

std::string VendorDevice::faultReason() const {
  const int code = fault_code_.load(std::memory_order_acquire);
  switch (fault_kind_.load(std::memory_order_acquire)) {
    case kReadError: return fmt::format("{}: reading the device: {} (SDK error {})", uri_, backend_->errorText(code), code);
    case kWriteError: return fmt::format("{}: setting the force: {} (SDK error {})", uri_, backend_->errorText(code), code);
    case kNonFiniteReading: return fmt::format("{}: the SDK returned a non-finite position or velocity", uri_);
    case kNonFiniteForce: return fmt::format("{}: a non-finite force reached the device (zero sent)", uri_);
    default: return {};
  }
}

}  // namespace hattr::device
