#pragma once
/// The plugin side of the driver ABI for plugins written in C++: write the driver as a
/// hattr::device::Device, give an open function, and HATTR_EXPORT_DEVICE_PLUGIN makes the C
/// table of hattr/device/plugin_abi.h from it. Exceptions stop at the boundary (open's become
/// last_error(NULL)); the host's simulated hand arrives as a HandScript. The in-tree plugins
/// (plugins/sim, plugins/replay) and every vendor plugin (through VendorDevice) use it.

#include <cstdint>
#include <memory>

#include "hattr/device/device.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/device/plugin_abi.h"

namespace hattr::device::plugin {

/// Opens the plugin's device from the URI's parameters (uri.scheme "plugin", uri.target the
/// plugin's path). `host_hand` is the host's simulated hand (null when there is none); it
/// outlives the device. Throws hattr::Error (or any std::exception) with a message for the user.
using OpenFn = std::unique_ptr<Device> (*)(const DeviceUri& uri, HandScript* host_hand);

/// The table for a plugin: `name` and `description` must be string literals. One per
/// shared object. Returns null for a host of another ABI version.
const hattr_plugin* exportTable(const char* name, const char* description, OpenFn open,
                                std::uint32_t host_abi_version) noexcept;

}  // namespace hattr::device::plugin

/// Exports the entry symbol of a plugin whose device `open_fn` opens.
#define HATTR_EXPORT_DEVICE_PLUGIN(name, description, open_fn)                                        \
  extern "C" __attribute__((visibility("default"))) const hattr_plugin* hattr_plugin_entry(            \
      std::uint32_t host_abi_version) {                                                                \
    return ::hattr::device::plugin::exportTable(name, description, open_fn, host_abi_version);        \
  }
