// A fake vendor SDK behind the vendor adapter, built as a driver plugin for the tests. It
// behaves as OpenHaptics does where it matters to the adapter: millimetres, a frame with y up
// and z toward the user, a scheduler thread that owns the servo loop (clock=device), limits in
// N and N/mm; and it fails on request. A point mass (50 g, 0.5 N·s/m) moves under the force
// it is sent, so a test can see forces arrive in the right direction and size.
// Keys: clock=device|host, rate_hz, start_mm=x,y,z (frame D), fail_open=TEXT,
//       error_after=N (reads after which every read fails with SDK error 0x0201),
//       error_after_total=N (the same, counting the reads of every device opened with this key
//       in the process: a fault in the middle of a study), nan_after=N (reads after which
//       positions are NaN), stall_after=N (frames after which
//       the scheduler stops calling), block_read_at=N&block_read_ms=M (read N blocks for M ms,
//       once: an SDK call that hangs for a while on the loop's own thread).
// Test hooks (extern "C"): fake_vendor_last_force_D, fake_vendor_frames, fake_vendor_reset_total_reads.

#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>

#include "hattr/core/error.hpp"
#include "hattr/device/plugin_export.hpp"
#include "hattr/device/vendor_adapter.hpp"

namespace {

using namespace hattr;
using namespace hattr::device;

constexpr int kFakeDeviceFault = 0x0201;

// What the test hooks read (the last plugin instance's).
std::atomic<double> g_force_D[3] = {0.0, 0.0, 0.0};
std::atomic<std::uint64_t> g_frames{0};
std::atomic<std::int64_t> g_total_reads{0};

class FakeVendor final : public VendorBackend {
 public:
  std::vector<std::string> keys() const override {
    return {"clock", "rate_hz", "start_mm", "fail_open", "error_after", "error_after_total", "nan_after", "stall_after",
            "block_read_at", "block_read_ms"};
  }

  VendorDescription open(const std::map<std::string, std::string>& params) override {
    const auto number = [&](const char* key, double fallback) {
      const auto it = params.find(key);
      return it == params.end() ? fallback : std::stod(it->second);
    };
    if (auto it = params.find("fail_open"); it != params.end()) {
      throw Error("fake SDK: " + it->second);
    }
    device_clock_ = params.count("clock") == 0 || params.at("clock") == "device";
    rate_hz_ = number("rate_hz", 1000.0);
    error_after_ = static_cast<std::int64_t>(number("error_after", -1));
    error_after_total_ = static_cast<std::int64_t>(number("error_after_total", -1));
    nan_after_ = static_cast<std::int64_t>(number("nan_after", -1));
    stall_after_ = static_cast<std::int64_t>(number("stall_after", -1));
    block_read_at_ = static_cast<std::int64_t>(number("block_read_at", -1));
    block_read_ms_ = number("block_read_ms", 0.0);
    if (auto it = params.find("start_mm"); it != params.end()) {
      std::sscanf(it->second.c_str(), "%lf,%lf,%lf", &p_mm_[0], &p_mm_[1], &p_mm_[2]);
    }
    for (auto& f : g_force_D) f.store(0.0);
    g_frames.store(0);

    VendorDescription d;
    d.model = "Fake Vendor Pen";
    d.length_unit_m = 1e-3;
    d.R_WD << 1, 0, 0,  //
        0, 0, -1,       // W's y (away from the writer) is D's -z (z toward the user)
        0, 1, 0;        // W's z (up) is D's y
    d.paper_origin_D = Vec3(0.0, -60.0, 0.0);
    d.workspace_min_D = Vec3(-80.0, -60.0, -50.0);
    d.workspace_max_D = Vec3(80.0, 60.0, 50.0);
    d.continuous_force_N = 0.88;
    d.peak_force_N = 3.3;
    d.max_stiffness_N_per_unit = 1.26;  // N/mm
    d.max_damping_N_s_per_unit = 0.005;
    d.nominal_rate_hz = rate_hz_;
    d.device_clock = device_clock_;
    return d;
  }

  // The mass moves by one period under the last force, then is read (in mm).
  int read(VendorReading& out) noexcept override {
    const std::int64_t n = reads_++;
    if (error_after_ >= 0 && n >= error_after_) return kFakeDeviceFault;
    if (error_after_total_ >= 0 && g_total_reads.fetch_add(1) >= error_after_total_) return kFakeDeviceFault;
    if (n == block_read_at_) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(block_read_ms_));
    const double h = 1.0 / rate_hz_;
    for (int i = 0; i < 3; ++i) {
      const double a = (force_D_[i] - 0.5 * v_mm_s_[i] * 1e-3) / 0.05;  // [m/s²]
      v_mm_s_[i] += h * a * 1e3;
      p_mm_[i] += h * v_mm_s_[i];
    }
    const double nan = std::nan("");
    const bool broken = nan_after_ >= 0 && n >= nan_after_;
    out.position_D = broken ? Vec3::Constant(nan) : Vec3(p_mm_[0], p_mm_[1], p_mm_[2]);
    out.velocity_D = Vec3(v_mm_s_[0], v_mm_s_[1], v_mm_s_[2]);
    return 0;
  }

  int write(const Vec3& force_D_N) noexcept override {
    for (int i = 0; i < 3; ++i) {
      force_D_[i] = force_D_N[i];
      g_force_D[i].store(force_D_N[i]);
    }
    return 0;
  }

  // The fake scheduler: a thread at the rate calling the frame, until stopped or stalled.
  void startScheduler(void (*frame)(void*), void* context) override {
    stop_.store(false);
    thread_ = std::thread([this, frame, context] {
      const auto period = std::chrono::nanoseconds(std::llround(1e9 / rate_hz_));
      auto deadline = std::chrono::steady_clock::now();
      for (std::int64_t n = 0; !stop_.load(); ++n) {
        if (stall_after_ < 0 || n < stall_after_) {
          frame(context);
          g_frames.fetch_add(1);
        }
        deadline += period;
        std::this_thread::sleep_until(deadline);
      }
    });
  }
  void stopScheduler() noexcept override {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  void close() noexcept override { (void)write(Vec3::Zero()); }
  std::string errorText(int code) const override {
    return code == kFakeDeviceFault ? "fake SDK: amplifier fault" : "fake SDK: unknown error";
  }

 private:
  bool device_clock_ = true;
  double rate_hz_ = 1000.0;
  std::int64_t error_after_ = -1, error_after_total_ = -1, nan_after_ = -1, stall_after_ = -1, reads_ = 0;
  std::int64_t block_read_at_ = -1;
  double block_read_ms_ = 0.0;
  double p_mm_[3] = {0.0, -55.0, 0.0};
  double v_mm_s_[3] = {0.0, 0.0, 0.0};
  double force_D_[3] = {0.0, 0.0, 0.0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace

extern "C" __attribute__((visibility("default"))) void fake_vendor_last_force_D(double out[3]) {
  for (int i = 0; i < 3; ++i) out[i] = g_force_D[i].load();
}
extern "C" __attribute__((visibility("default"))) std::uint64_t fake_vendor_frames() { return g_frames.load(); }
extern "C" __attribute__((visibility("default"))) void fake_vendor_reset_total_reads() { g_total_reads.store(0); }

HATTR_EXPORT_DEVICE_PLUGIN("fake-vendor", "a fake vendor SDK for the adapter's tests", openVendorDevice<FakeVendor>)
