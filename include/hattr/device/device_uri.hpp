#pragma once
/// Devices are opened by URI so apps and configurations can name them:
///   sim://pen?mass_kg=0.045&damping_N_s_per_m=1&quantum_m=2.3e-5&continuous_force_N=1.75
///   sim://planar (the open pen's plant), udp://HOST:PORT?key=FILE (a served pen),
///   plugin:/path/lib.so or plugin:NAME (a driver plugin), serial://PORT (the open pen).

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "hattr/device/simulated_device.hpp"

namespace hattr::device {

struct DeviceUri {
  std::string scheme;                        ///< "sim", "udp", "plugin", "serial"
  std::string target;                        ///< "pen", "host:port", "/path/lib.so"
  std::map<std::string, std::string> query;  ///< key=value parameters
};

/// Splits a URI; throws InputError naming what is accepted when it is malformed.
DeviceUri parseDeviceUri(std::string_view uri);

/// The simulated pen's parameters from a sim:// URI (defaults for absent keys). Unknown
/// keys and out-of-range values throw InputError naming the key, the range and the value.
SimulatedPenParams simulatedPenParams(const DeviceUri& uri);

/// Opens the device a URI names. `hand` drives a simulated pen (may be null). Throws
/// InputError for an unknown or malformed URI, listing what is accepted.
std::unique_ptr<Device> openDevice(std::string_view uri, HandScript* hand);

/// The limits a device declares without being opened: a simulated pen's (sim://pen, sim://planar)
/// from its URI. nullopt for every other device, whose limits are known once it is open (a plugin
/// loads its SDK, a udp:// device asks its server, the open pen says its linkage): a trial reads
/// them from the device it opens (session::TrialEnvironment::bindLimits). Throws InputError for a
/// malformed URI or sim:// key.
std::optional<DeviceLimits> limitsWithoutOpening(std::string_view uri);

/// Help text listing the accepted URIs and sim:// keys.
std::string deviceUriHelp();

}  // namespace hattr::device
