#pragma once
/// The host side of driver plugins: `plugin:/path/libX.so?key=value&...` opens a shared object
/// that speaks the C ABI of hattr/device/plugin_abi.h and wraps it as a Device. Every loading
/// failure is an InputError that names the file and says what went wrong: file missing, not a
/// shared object, entry symbol missing, ABI version mismatch (both versions), open failed (the
/// plugin's own message). At run time a plugin that returns a non-finite state, an error or a
/// timeout makes read() return kFault, and faultReason() says which. See docs/devices.md.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/device/device.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"

namespace hattr::device {

/// What a plugin says about itself.
struct PluginInfo {
  std::string path;
  std::string name;
  std::string description;
  std::uint32_t abi_version = 0;
};

/// Where plugins are looked for when a URI names one without a path (`plugin:sim` means
/// libhattr_sim_plugin.so): the folders of $HATTR_PLUGIN_PATH (colon-separated), then the plugin
/// folder of the prefix this program is in, LIBDIR/hattr/plugins (an installed prefix's, or the
/// build folder's: hattr/core/install_layout.hpp).
std::vector<std::string> pluginSearchPath();
/// The file a plugin URI's target names: a path as it is; a bare name through the search path.
/// Throws InputError naming the folders searched when a bare name is not found.
std::string resolvePlugin(const std::string& target);
/// Every plugin in the search path (for `hattr devices`), skipping files that are not plugins.
std::vector<struct PluginInfo> findPlugins();

/// Loads the plugin at `path` and reads its table without opening a device. Throws InputError.
PluginInfo inspectPlugin(const std::string& path);

/// Opens the device of a plugin: URI (parsed and as typed). `hand` is offered to simulated
/// devices through the ABI's host hand (may be null: nobody's simulated hand holds the pen).
/// Throws InputError for every loading or opening failure.
std::unique_ptr<Device> openPluginDevice(const DeviceUri& uri, std::string_view uri_text, HandScript* hand);

}  // namespace hattr::device
