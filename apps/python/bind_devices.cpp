// hattr.servo_check and hattr.check_device: the library's checks (hattr::ops), their results as
// the CLI's --json prints them.

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include <pybind11/functional.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "hattr/core/units.hpp"
#include "hattr/ops/device_check.hpp"
#include "hattr/ops/servo_check.hpp"

namespace hattr::python {

void bindDevices(py::module_& m) {
  m.def(
      "servo_check",
      [](const std::string& device, double rate_hz, double seconds, const std::optional<std::filesystem::path>& world,
         const std::string& realtime, int cpu, double spin_us) {
        const ops::ServoCheckOptions options{
            .rate_hz = rate_hz,
            .seconds = seconds,
            .device = device,
            .world = world.value_or(std::filesystem::path()),
            .realtime = {.policy = servo::parseRealtimePolicy(realtime),
                         .cpu = cpu,
                         .final_spin = std::chrono::nanoseconds(units::secondsToNanoseconds(spin_us * 1e-6))}};
        nlohmann::json json;
        {
          py::gil_scoped_release unlocked;
          json = ops::runServoCheck(options).toJson();
        }
        return toPython(json);
      },
      py::arg("device") = "sim://pen", py::kw_only(), py::arg("rate_hz") = 1000.0, py::arg("seconds") = 5.0,
      py::arg("world") = py::none(), py::arg("realtime") = "try", py::arg("cpu") = -1, py::arg("spin_us") = 0.0,
      "The servo check, as `hattr servo-check --json`: a bare sleep loop (the floor), then the full pipeline on "
      "`device` for `seconds` each; returns {floor, loop, ratio_p99, [link], verdicts, verdict, ...} "
      "(docs/realtime.md). realtime: 'require', 'try' or 'skip'. Releases the GIL.");

  m.def(
      "check_device",
      [](const std::string& uri, double seconds, double force_N, double rate_hz,
         const std::optional<std::function<std::optional<bool>()>>& confirm) {
        ops::DeviceCheckOptions options{.uri = uri, .seconds = seconds, .force_N = force_N, .rate_hz = rate_hz};
        if (confirm) {
          options.confirm = [&confirm] {
            py::gil_scoped_acquire locked;
            return (*confirm)();
          };
        }
        nlohmann::json json;
        {
          py::gil_scoped_release unlocked;
          json = ops::runDeviceCheck(options).toJson();
        }
        return toPython(json);
      },
      py::arg("uri"), py::kw_only(), py::arg("seconds") = 2.0, py::arg("force_N") = 0.2, py::arg("rate_hz") = 0.0,
      py::arg("confirm") = py::none(),
      "The device check, as `hattr devices check URI --json`: its limits and rate, the loop's jitter for "
      "`seconds`, a gentle upward force of force_N, then `confirm()` (if given: did the person feel it? True, "
      "False or None for no answer); returns {limits, period_error_us, force_test, verdicts, verdict, ok, ...} "
      "(docs/devices.md). rate_hz 0: the device's nominal rate. Releases the GIL.");
}

}  // namespace hattr::python
