// A plugin built for a future ABI (version 99): the host must refuse it, naming both versions.
#include <cstdint>

#include "hattr/device/plugin_abi.h"

namespace {
hattr_plugin g_table{99u, sizeof(hattr_plugin), "future", "speaks ABI 99", nullptr, nullptr, nullptr,
                     nullptr, nullptr, nullptr, nullptr, nullptr, nullptr};
}

extern "C" __attribute__((visibility("default"))) const hattr_plugin* hattr_plugin_entry(std::uint32_t) {
  return &g_table;
}
