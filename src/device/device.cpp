#include "hattr/device/device.hpp"

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::device {

// Only device-clocked devices own a clock; asking any other device is a bug in the caller.
void Device::startClock(DeviceTickFn /*tick*/, void* /*context*/) {
  throw Error(fmt::format("device {} does not run a clock of its own", uri()));
}

}  // namespace hattr::device
