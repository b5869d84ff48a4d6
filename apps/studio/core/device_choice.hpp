#pragma once
/// Choosing the studio's device by URI: every kind the library opens (sim://pen, plugin:,
/// udp://). The mouse or tablet hand holds a simulated pen (sim://pen, the sim plugin, a
/// simulated pen served over udp://); a hardware pen is held by the person, and the mouse then
/// only moves the view. GUI thread; throws InputError with the library's messages.

#include <string_view>

#include "hattr/device/device_uri.hpp"

namespace hattr::studio {

/// The device the studio starts with.
inline constexpr const char* kDefaultDeviceUri = "sim://pen";

/// Opens `uri` once as openDevice does (the library's messages, e.g. `device URI "usb://x":
/// unknown scheme ...`; a plugin that does not load; a device server that does not answer)
/// and returns the device's limits. Throws InputError.
DeviceLimits validateStudioDevice(std::string_view uri);

}  // namespace hattr::studio
