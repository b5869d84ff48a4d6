// 3D Systems OpenHaptics (HD API) driver plugin: PHANToM / Touch / Geomagic pens.
// Built only with -DHATTR_OPENHAPTICS_SDK=<SDK folder>; the SDK is not on the machines hattr is
// built and tested on, so this file is kept to the SDK calls. Units, frames, limits, clocking
// and errors are the tested VendorDevice adapter's (include/hattr/device/vendor_adapter.hpp).
// URI: plugin:openhaptics[?device=NAME][&paper_origin=x,y,z][&max_force_N=F]
//   device: the device's name in the OpenHaptics configuration (default: the default device).
// The HD scheduler owns the servo thread: the host's tick runs inside its callback, between
// hdBeginFrame and hdEndFrame, at the scheduler's rate (HD_UPDATE_RATE).

#include <HD/hd.h>

#include <string>

#include "hattr/core/error.hpp"
#include "hattr/device/plugin_export.hpp"
#include "hattr/device/vendor_adapter.hpp"

namespace {

using namespace hattr;
using namespace hattr::device;

/// The HD error pending now as a code, 0 for none (clears it).
int pendingHdError() noexcept {
  const HDErrorInfo error = hdGetError();
  return HD_DEVICE_ERROR(error) ? static_cast<int>(error.errorCode) : 0;
}

class OpenHapticsBackend final : public VendorBackend {
 public:
  std::vector<std::string> keys() const override { return {"device"}; }

  VendorDescription open(const std::map<std::string, std::string>& params) override {
    const auto name = params.find("device");
    device_ = hdInitDevice(name == params.end() ? HD_DEFAULT_DEVICE : name->second.c_str());
    if (const int code = pendingHdError()) throw Error("hdInitDevice: " + errorText(code));
    hdMakeCurrentDevice(device_);
    hdEnable(HD_FORCE_OUTPUT);

    // Limits in the SDK's units: mm, N, N/mm; the frame: x right, y up, z toward the user.
    VendorDescription d;
    d.model = hdGetString(HD_DEVICE_MODEL_TYPE);
    HDdouble workspace_mm[6] = {};
    hdGetDoublev(HD_USABLE_WORKSPACE_DIMENSIONS, workspace_mm);
    d.workspace_min_D = Vec3(workspace_mm[0], workspace_mm[1], workspace_mm[2]);
    d.workspace_max_D = Vec3(workspace_mm[3], workspace_mm[4], workspace_mm[5]);
    hdGetDoublev(HD_NOMINAL_MAX_CONTINUOUS_FORCE, &d.continuous_force_N);
    hdGetDoublev(HD_NOMINAL_MAX_FORCE, &d.peak_force_N);
    hdGetDoublev(HD_NOMINAL_MAX_STIFFNESS, &d.max_stiffness_N_per_unit);
    hdGetDoublev(HD_NOMINAL_MAX_DAMPING, &d.max_damping_N_s_per_unit);
    HDint rate_hz = 1000;
    hdGetIntegerv(HD_UPDATE_RATE, &rate_hz);
    if (const int code = pendingHdError()) throw Error("reading the device's limits: " + errorText(code));
    d.nominal_rate_hz = rate_hz;
    d.length_unit_m = 1e-3;
    d.R_WD << 1, 0, 0,  // W's x: right
        0, 0, -1,       // W's y (away from the writer): -z (z points toward the user)
        0, 1, 0;        // W's z (up): y
    // hattr's reading: the paper lies at the floor of the usable workspace, centred in x and z.
    d.paper_origin_D = Vec3((workspace_mm[0] + workspace_mm[3]) / 2, workspace_mm[1], (workspace_mm[2] + workspace_mm[5]) / 2);
    d.device_clock = true;
    return d;
  }

  // Inside the scheduler's frame (the only place HD allows these calls).
  int read(VendorReading& out) noexcept override {
    HDdouble p[3], v[3];
    HDint buttons = 0;
    hdGetDoublev(HD_CURRENT_POSITION, p);
    hdGetDoublev(HD_CURRENT_VELOCITY, v);
    hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
    out.position_D = Vec3(p[0], p[1], p[2]);
    out.velocity_D = Vec3(v[0], v[1], v[2]);
    out.buttons = static_cast<std::uint32_t>(buttons);
    return pendingHdError();
  }

  int write(const Vec3& force_D_N) noexcept override {
    const HDdouble f[3] = {force_D_N.x(), force_D_N.y(), force_D_N.z()};
    hdSetDoublev(HD_CURRENT_FORCE, f);
    return pendingHdError();
  }

  void startScheduler(void (*frame)(void*), void* context) override {
    frame_ = frame;
    frame_context_ = context;
    callback_ = hdScheduleAsynchronous(&OpenHapticsBackend::servoCallback, this, HD_MAX_SCHEDULER_PRIORITY);
    hdStartScheduler();
    if (const int code = pendingHdError()) throw Error("starting the HD scheduler: " + errorText(code));
  }

  void stopScheduler() noexcept override {
    hdStopScheduler();
    if (callback_ != 0) hdUnschedule(callback_);
    callback_ = 0;
  }

  void close() noexcept override {
    if (device_ != HD_INVALID_HANDLE) hdDisableDevice(device_);
    device_ = HD_INVALID_HANDLE;
  }

  std::string errorText(int code) const override {
    const char* text = hdGetErrorString(static_cast<HDerror>(code));
    return text ? text : "unknown HD error";
  }

 private:
  static HDCallbackCode HDCALLBACK servoCallback(void* data) {
    auto* self = static_cast<OpenHapticsBackend*>(data);
    hdBeginFrame(self->device_);
    self->frame_(self->frame_context_);
    hdEndFrame(self->device_);
    return HD_CALLBACK_CONTINUE;
  }

  HHD device_ = HD_INVALID_HANDLE;
  HDSchedulerHandle callback_ = 0;
  void (*frame_)(void*) = nullptr;
  void* frame_context_ = nullptr;
};

}  // namespace

HATTR_EXPORT_DEVICE_PLUGIN("openhaptics", "3D Systems OpenHaptics (HD API) pens: PHANToM, Touch",
                           openVendorDevice<OpenHapticsBackend>)
