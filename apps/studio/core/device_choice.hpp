#pragma once
/// Choosing the studio's device by URI (hattr::device::parseDeviceUri). The mouse or tablet
/// hand can only hold a simulated pen, so only sim:// URIs are accepted; udp:// and plugin:
/// are refused with the library's "reserved" message. GUI thread; throws InputError.

#include <string_view>

#include "hattr/device/device_uri.hpp"

namespace hattr::studio {

/// The device the studio starts with.
inline constexpr const char* kDefaultDeviceUri = "sim://pen";

/// Checks `uri` as openDevice would (the library's messages, e.g. `device URI "usb://x":
/// unknown scheme ...`) and returns the simulated pen's parameters (its limits). Throws
/// InputError for anything the studio's hand cannot drive.
device::SimulatedPenParams validateStudioDevice(std::string_view uri);

}  // namespace hattr::studio
