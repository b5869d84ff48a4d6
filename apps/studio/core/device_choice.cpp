#include "core/device_choice.hpp"

#include <memory>

#include "hattr/device/device.hpp"

namespace hattr::studio {

DeviceLimits validateStudioDevice(std::string_view uri) {
  // openDevice names every refusal the library's way (unknown scheme, bad key, no plugin).
  const std::unique_ptr<device::Device> probe = device::openDevice(uri, nullptr);
  return probe->limits();
}

}  // namespace hattr::studio
