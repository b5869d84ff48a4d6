#include "core/device_choice.hpp"

#include <memory>

#include "hattr/device/device.hpp"

namespace hattr::studio {

device::SimulatedPenParams validateStudioDevice(std::string_view uri) {
  // openDevice names every refusal the library's way (unknown scheme, reserved, bad key).
  const std::unique_ptr<device::Device> probe = device::openDevice(uri, nullptr);
  return device::simulatedPenParams(device::parseDeviceUri(uri));
}

}  // namespace hattr::studio
