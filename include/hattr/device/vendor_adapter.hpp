#pragma once
/// The shared adapter behind every vendor driver plugin (plugins/openhaptics,
/// plugins/forcedimension): a vendor plugin implements VendorBackend — a thin layer of SDK calls
/// in the SDK's own units and frame — and VendorDevice does everything else, tested here with a
/// fake vendor (tests/device/fake_vendor_plugin.cpp):
///   - units: SDK lengths (e.g. mm) to metres, N/mm to N/m; forces in newtons both sides;
///   - frames: the SDK's frame D to hattr's W (paper plane z = 0, x right, y away from the
///     writer, z up) by a rotation and the paper's origin in D;
///   - limits: the SDK's workspace, forces, stiffness and rate as DeviceLimits in SI, lowered
///     (never raised) by the URI's max_force_N;
///   - clocking: for an SDK that owns the servo thread (OpenHaptics' scheduler), the host's
///     tick runs inside the SDK's frame callback, and a frame the host did not write gets zero
///     force;
///   - errors: SDK error codes become kFault with the SDK's own text in faultReason(); a
///     non-finite reading is a fault; the force is clamped to the device's peak force as the
///     last line of defence (the host's safety path clamps first).
/// Vendor plugins export it with HATTR_EXPORT_DEVICE_PLUGIN and openVendorDevice.

#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "hattr/device/device.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"

namespace hattr::device {

/// A vendor's device as its SDK describes it, in the SDK's units and frame D.
struct VendorDescription {
  std::string model;                                        ///< for messages ("PHANTOM Omni")
  double length_unit_m = 1e-3;                              ///< one SDK length unit [m] (mm: 1e-3)
  Eigen::Matrix3d R_WD = Eigen::Matrix3d::Identity();       ///< rotation from D to W
  Vec3 paper_origin_D = Vec3::Zero();                       ///< W's origin in D [SDK units]
  Vec3 workspace_min_D = Vec3::Constant(-80.0);             ///< workspace box in D [SDK units]
  Vec3 workspace_max_D = Vec3::Constant(80.0);
  double continuous_force_N = 0.0;
  double peak_force_N = 0.0;
  double max_stiffness_N_per_unit = 0.0;                    ///< e.g. HD_NOMINAL_MAX_STIFFNESS [N/mm]
  double max_damping_N_s_per_unit = 0.0;                    ///< e.g. HD_NOMINAL_MAX_DAMPING [N·s/mm]
  double nominal_rate_hz = 1000.0;
  double mass_kg = 0.045;                                   ///< apparent mass at the tip, if known
  double damping_N_s_per_m = 1.0;                           ///< physical damping, if known [N·s/m]
  bool device_clock = false;                                ///< the SDK calls us once per period
  DeviceCapabilities capabilities;
};

/// One reading in the SDK's units and frame.
struct VendorReading {
  Vec3 position_D = Vec3::Zero();   ///< [SDK length units]
  Vec3 velocity_D = Vec3::Zero();   ///< [SDK length units / s]
  std::uint32_t buttons = 0;
};

/// The SDK calls behind a vendor plugin. Thread rules as for Device.
class VendorBackend {
 public:
  virtual ~VendorBackend() = default;
  /// [main-thread] The URI keys the backend accepts (the adapter adds its own).
  [[nodiscard]] virtual std::vector<std::string> keys() const { return {}; }
  /// [main-thread] Opens the SDK's device with the backend's URI keys. Throws hattr::Error with
  /// the SDK's message.
  virtual VendorDescription open(const std::map<std::string, std::string>& params) = 0;
  /// [servo-thread] Reads the device. Returns 0, or an SDK error code.
  virtual int read(VendorReading& out) noexcept = 0;
  /// [servo-thread] Commands a force [N] in frame D. Returns 0, or an SDK error code.
  virtual int write(const Vec3& force_D_N) noexcept = 0;
  /// [main-thread] Device clock only: the SDK calls frame(context) once per period from its
  /// thread, inside whatever brackets its reads and writes need (hdBeginFrame/hdEndFrame).
  /// Throws hattr::Error with the SDK's message.
  virtual void startScheduler(void (*frame)(void* context), void* context);
  virtual void stopScheduler() noexcept {}
  /// [main-thread] Zero force and release the SDK.
  virtual void close() noexcept = 0;
  /// [any-thread] The SDK's text for an error code.
  [[nodiscard]] virtual std::string errorText(int code) const = 0;
};

/// A vendor SDK's device as a hattr Device (see the file comment).
class VendorDevice final : public Device {
 public:
  /// Opens the backend with the URI's keys. Adapter keys: max_force_N (lower the force limit),
  /// paper_origin (the paper's origin in the SDK frame, SDK units, "x,y,z"). Throws InputError
  /// for unknown keys (listing all accepted) or bad values, hattr::Error if the SDK fails.
  VendorDevice(std::unique_ptr<VendorBackend> backend, const DeviceUri& uri);
  ~VendorDevice() override;
  VendorDevice(const VendorDevice&) = delete;
  VendorDevice& operator=(const VendorDevice&) = delete;

  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override;
  DeviceStatus write(const Vec3& f_on_pen_W) noexcept override;
  const DeviceLimits& limits() const noexcept override { return limits_; }
  DeviceCapabilities capabilities() const noexcept override { return description_.capabilities; }
  const std::string& uri() const noexcept override { return uri_; }
  DeviceClocking clocking() const noexcept override {
    return description_.device_clock ? DeviceClocking::kDeviceClock : DeviceClocking::kHostRealTime;
  }
  void startClock(DeviceTickFn tick, void* context) override;
  void stopClock() noexcept override;
  std::string faultReason() const override;

  /// Frames of the SDK's clock so far, and those in which the host wrote no force (zeroed).
  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_.load(); }
  [[nodiscard]] std::uint64_t unwrittenFrames() const noexcept { return unwritten_frames_.load(); }

 private:
  void describeInSi(double cap, const std::string& cap_text);
  static void onFrame(void* context) noexcept;
  DeviceStatus fail(int kind, int code) noexcept;

  std::unique_ptr<VendorBackend> backend_;
  VendorDescription description_;
  DeviceLimits limits_;
  std::string uri_;
  double force_limit_N_ = 0.0;
  // Device clock: the host's tick, the clock's start, whether the host wrote in this frame.
  DeviceTickFn tick_ = nullptr;
  void* tick_context_ = nullptr;
  std::chrono::nanoseconds clock_start_{0};
  bool wrote_in_frame_ = false;
  bool clock_running_ = false;
  std::atomic<bool> stopping_{false};  // the last frames write zero, without the host's tick
  std::atomic<std::uint64_t> frames_{0};
  std::atomic<std::uint64_t> unwritten_frames_{0};
  std::atomic<int> fault_kind_{0};
  std::atomic<int> fault_code_{0};
};

/// For HATTR_EXPORT_DEVICE_PLUGIN: the open function of a vendor plugin whose backend is B.
template <class Backend>
std::unique_ptr<Device> openVendorDevice(const DeviceUri& uri, HandScript* /*host_hand: people hold real pens*/) {
  return std::make_unique<VendorDevice>(std::make_unique<Backend>(), uri);
}

}  // namespace hattr::device
