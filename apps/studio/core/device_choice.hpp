#pragma once
/// Choosing the studio's device by URI: every kind the library opens (sim://pen, sim://planar,
/// plugin:, udp://, serial://). The mouse or tablet hand holds a simulated pen (sim://pen, the sim
/// plugin, a simulated pen served over udp://); a hardware pen is held by the person, and the
/// mouse then only moves the view. The device is opened by each run of the rig (once a run);
/// MainWindow::setDevice reports the library's messages when it does not open.

namespace hattr::studio {

/// The device the studio starts with.
inline constexpr const char* kDefaultDeviceUri = "sim://pen";

}  // namespace hattr::studio
