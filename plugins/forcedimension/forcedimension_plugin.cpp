// Force Dimension (DHD API) driver plugin: omega, delta, sigma and Novint Falcon devices.
// Built only with -DHATTR_FORCEDIMENSION_SDK=<SDK folder>; the SDK is not on the machines hattr
// is built and tested on, so this file is kept to the SDK calls. Units, frames, limits, clocking
// and errors are the tested VendorDevice adapter's (include/hattr/device/vendor_adapter.hpp).
// URI: plugin:forcedimension[?peak_force_N=F&continuous_force_N=F&stiffness_N_per_m=K&rate_hz=R]
//      [&paper_origin=x,y,z][&max_force_N=F]
// DHD reports no force or stiffness limits, so they come from the URI: take them from your
// device's data sheet. The defaults are deliberately low (2 N peak, 1 N continuous, 1000 N/m).
// DHD is polled by the host's real-time thread (host clock).

#include <dhdc.h>

#include <cstdlib>
#include <string>

#include "hattr/core/error.hpp"
#include "hattr/device/plugin_export.hpp"
#include "hattr/device/vendor_adapter.hpp"

namespace {

using namespace hattr;
using namespace hattr::device;

double numberOr(const std::map<std::string, std::string>& params, const char* key, double fallback) {
  const auto it = params.find(key);
  if (it == params.end()) return fallback;
  char* end = nullptr;
  const double value = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str() || *end != '\0' || !(value > 0.0)) {
    throw InputError(std::string("forcedimension: key ") + key + ": expected a positive number, got \"" + it->second + "\"");
  }
  return value;
}

class ForceDimensionBackend final : public VendorBackend {
 public:
  std::vector<std::string> keys() const override {
    return {"peak_force_N", "continuous_force_N", "stiffness_N_per_m", "rate_hz"};
  }

  VendorDescription open(const std::map<std::string, std::string>& params) override {
    VendorDescription d;
    d.peak_force_N = numberOr(params, "peak_force_N", 2.0);
    d.continuous_force_N = numberOr(params, "continuous_force_N", 1.0);
    d.max_stiffness_N_per_unit = numberOr(params, "stiffness_N_per_m", 1000.0);  // unit: m
    d.nominal_rate_hz = numberOr(params, "rate_hz", 1000.0);
    id_ = static_cast<char>(dhdOpen());
    if (id_ < 0) throw Error(std::string("dhdOpen: ") + dhdErrorGetLastStr());
    if (dhdEnableForce(DHD_ON, id_) < 0) {
      const std::string why = dhdErrorGetLastStr();
      close();
      throw Error("dhdEnableForce: " + why);
    }

    // DHD works in SI: metres and newtons; its frame: x toward the user, y right, z up.
    d.model = dhdGetSystemName(id_) ? dhdGetSystemName(id_) : "Force Dimension device";
    d.length_unit_m = 1.0;
    d.R_WD << 0, 1, 0,  // W's x (right): y
        -1, 0, 0,       // W's y (away from the writer): -x
        0, 0, 1;        // W's z (up): z
    d.workspace_min_D = Vec3(-0.08, -0.08, -0.08);
    d.workspace_max_D = Vec3(0.08, 0.08, 0.08);
    // hattr's reading: the paper lies 40 mm below the device's centre.
    d.paper_origin_D = Vec3(0.0, 0.0, -0.04);
    d.device_clock = false;
    return d;
  }

  int read(VendorReading& out) noexcept override {
    double p[3], v[3];
    if (dhdGetPosition(&p[0], &p[1], &p[2], id_) < 0) return dhdErrorGetLast();
    if (dhdGetLinearVelocity(&v[0], &v[1], &v[2], id_) < 0) return dhdErrorGetLast();
    out.position_D = Vec3(p[0], p[1], p[2]);
    out.velocity_D = Vec3(v[0], v[1], v[2]);
    out.buttons = dhdGetButton(0, id_) == DHD_ON ? 1u : 0u;
    return 0;
  }

  // A saturated motor (a positive return) is not an error: the adapter already clamps.
  int write(const Vec3& force_D_N) noexcept override {
    return dhdSetForce(force_D_N.x(), force_D_N.y(), force_D_N.z(), id_) < 0 ? dhdErrorGetLast() : 0;
  }

  void close() noexcept override {
    if (id_ < 0) return;
    (void)dhdSetForce(0.0, 0.0, 0.0, id_);
    dhdClose(id_);
    id_ = -1;
  }

  std::string errorText(int code) const override {
    const char* text = dhdErrorGetStr(code);
    return text ? text : "unknown DHD error";
  }

 private:
  char id_ = -1;
};

}  // namespace

HATTR_EXPORT_DEVICE_PLUGIN("forcedimension", "Force Dimension (DHD API) devices: omega, delta, sigma, Falcon",
                           openVendorDevice<ForceDimensionBackend>)
