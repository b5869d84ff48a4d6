#include "hattr/device/device_uri.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/device/plugin_device.hpp"
#include "hattr/device/serial_device.hpp"
#include "hattr/device/simulated_planar_device.hpp"
#include "hattr/device/udp_device.hpp"

namespace hattr::device {
namespace {

constexpr std::string_view kAccepted =
    "sim://pen[?key=value&...] (simulated force-feedback pen); "
    "sim://planar (the open pen's plant, simulated with ideal electronics); "
    "udp://HOST:PORT?key=FILE[&hold_ms=5&timeout_s=1] (a pen served by `hattr device serve`); "
    "serial://PORT[?baud=1000000&...] (the open pen on a serial port, docs/hardware.md); "
    "plugin:/path/libX.so[?key=value&...] or plugin:NAME (a driver plugin: hardware, sim, replay)";

struct SimKey {
  std::string_view key;
  double min;
  double max;
  double* (*field)(SimulatedPenParams&);
  std::string_view help;
};

constexpr SimKey kSimKeys[] = {
    {"mass_kg", 1e-3, 10.0, [](SimulatedPenParams& p) { return &p.mass_kg; }, "apparent mass at the tip [kg]"},
    {"damping_N_s_per_m", 0.0, 100.0, [](SimulatedPenParams& p) { return &p.damping_N_s_per_m; },
     "viscous damping of the mechanism [N·s/m]"},
    {"quantum_m", 0.0, 1e-3, [](SimulatedPenParams& p) { return &p.position_quantum_m; },
     "position-sensor resolution [m] (0: none)"},
    {"continuous_force_N", 0.01, 100.0, [](SimulatedPenParams& p) { return &p.limits.continuous_force_N; },
     "sustainable force [N]"},
    {"peak_force_N", 0.01, 100.0, [](SimulatedPenParams& p) { return &p.limits.peak_force_N; }, "peak force [N]"},
    {"max_stiffness_N_per_m", 1.0, 1e6, [](SimulatedPenParams& p) { return &p.limits.max_stiffness_N_per_m; },
     "largest stably rendered stiffness [N/m]"},
    {"max_damping_N_s_per_m", 0.0, 1e4, [](SimulatedPenParams& p) { return &p.limits.max_damping_N_s_per_m; },
     "largest stably rendered damping [N·s/m]"},
    {"hand_stiffness_N_per_m", 0.0, 1e5, [](SimulatedPenParams& p) { return &p.hand.stiffness_N_per_m; },
     "stiffness of the simulated hand [N/m]"},
    {"hand_damping_N_s_per_m", 0.0, 1e3, [](SimulatedPenParams& p) { return &p.hand.damping_N_s_per_m; },
     "damping of the simulated hand [N·s/m]"},
    {"hand_press_tau_s", 0.0, 1.0, [](SimulatedPenParams& p) { return &p.hand.press_time_constant_s; },
     "time constant of the hand's pressing force [s]"},
    {"hand_max_force_N", 0.01, 1000.0, [](SimulatedPenParams& p) { return &p.hand.max_force_N; },
     "the most the simulated hand pushes with [N]"},
    {"hand_ease_begin_m", 0.0, 1.0, [](SimulatedPenParams& p) { return &p.hand.press_ease_begin_m; },
     "depth under the writing plane where the hand's press begins to ease off [m]"},
    {"hand_ease_end_m", 1e-4, 1.0, [](SimulatedPenParams& p) { return &p.hand.press_ease_end_m; },
     "depth where the hand's press has eased off to nothing [m]"},
    {"timeout_s", 1e-4, 10.0, [](SimulatedPenParams& p) { return &p.command_timeout_s; },
     "force drops to zero without a new command for this long [s]"},
};

std::string simKeyList() {
  std::string keys;
  for (const auto& k : kSimKeys) keys += (keys.empty() ? "" : ", ") + std::string(k.key);
  return keys;
}

/// %XX escapes decoded (a path or a name with spaces); a broken escape is refused.
std::string percentDecoded(std::string_view uri, std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '%') {
      out += text[i];
      continue;
    }
    unsigned value = 0;
    const char* first = text.data() + i + 1;
    const auto [end, ec] = i + 2 < text.size() ? std::from_chars(first, first + 2, value, 16)
                                                : std::from_chars_result{first, std::errc::invalid_argument};
    HATTR_THROW_UNLESS(ec == std::errc{} && end == first + 2,
                       "device URI \"{}\": expected %XX (two hex digits) in \"{}\"", uri, text);
    out += static_cast<char>(value);
    i += 2;
  }
  return out;
}

}  // namespace

DeviceUri parseDeviceUri(std::string_view uri) {
  DeviceUri out;
  std::string_view rest;
  if (uri.starts_with("plugin:")) {
    out.scheme = "plugin";
    rest = uri.substr(7);
  } else {
    const auto sep = uri.find("://");
    HATTR_THROW_UNLESS(sep != std::string_view::npos && sep > 0,
                       "device URI \"{}\": expected scheme://target, accepted: {}", uri, kAccepted);
    out.scheme = uri.substr(0, sep);
    rest = uri.substr(sep + 3);
  }
  const auto question = rest.find('?');
  out.target = percentDecoded(uri, rest.substr(0, question));
  if (question != std::string_view::npos) {
    std::string_view query = rest.substr(question + 1);
    while (!query.empty()) {
      const auto amp = query.find('&');
      const std::string_view pair = query.substr(0, amp);
      const auto eq = pair.find('=');
      HATTR_THROW_UNLESS(eq != std::string_view::npos && eq > 0,
                         "device URI \"{}\": expected key=value in the query, got \"{}\"", uri, pair);
      HATTR_THROW_UNLESS(out.query.emplace(percentDecoded(uri, pair.substr(0, eq)), percentDecoded(uri, pair.substr(eq + 1))).second,
                         "device URI \"{}\": key \"{}\" appears twice", uri, pair.substr(0, eq));
      query = amp == std::string_view::npos ? std::string_view{} : query.substr(amp + 1);
    }
  }
  return out;
}

SimulatedPenParams simulatedPenParams(const DeviceUri& uri) {
  SimulatedPenParams params;
  for (const auto& [key, text] : uri.query) {
    const std::string_view name = key;  // clang 14 cannot capture a structured binding
    const auto* spec = std::find_if(std::begin(kSimKeys), std::end(kSimKeys), [name](const SimKey& k) { return k.key == name; });
    HATTR_THROW_UNLESS(spec != std::end(kSimKeys), "sim://{}: unknown key \"{}\": expected one of {}", uri.target, key,
                       simKeyList());
    double value = 0.0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    HATTR_THROW_UNLESS(ec == std::errc{} && end == text.data() + text.size() && std::isfinite(value) &&
                           value >= spec->min && value <= spec->max,
                       "sim://{}: key {}: expected a number in [{}, {}], got \"{}\"", uri.target, key, spec->min,
                       spec->max, text);
    *spec->field(params) = value;
  }
  params.limits.mass_kg = params.mass_kg;
  params.limits.damping_N_s_per_m = params.damping_N_s_per_m;
  HATTR_THROW_UNLESS(params.limits.continuous_force_N <= params.limits.peak_force_N,
                     "sim://{}: continuous_force_N ({}) must not exceed peak_force_N ({})", uri.target,
                     params.limits.continuous_force_N, params.limits.peak_force_N);
  HATTR_THROW_UNLESS(params.hand.press_ease_end_m > params.hand.press_ease_begin_m,
                     "sim://{}: hand_ease_end_m ({}) must lie beyond hand_ease_begin_m ({})", uri.target,
                     params.hand.press_ease_end_m, params.hand.press_ease_begin_m);
  return params;
}

std::unique_ptr<Device> openDevice(std::string_view uri_text, HandScript* hand) {
  const DeviceUri uri = parseDeviceUri(uri_text);
  if (uri.scheme == "sim" && uri.target == "planar") {
    return std::make_unique<SimulatedPlanarDevice>(simulatedPlanarParams(uri), hand, std::string(uri_text));
  }
  if (uri.scheme == "sim") {
    HATTR_THROW_UNLESS(uri.target == "pen", "device URI \"{}\": the simulator offers sim://pen and sim://planar, got sim://{}",
                       uri_text, uri.target);
    return std::make_unique<SimulatedDevice>(simulatedPenParams(uri), hand, std::string(uri_text));
  }
  if (uri.scheme == "plugin") return openPluginDevice(uri, uri_text, hand);
  if (uri.scheme == "udp") return openUdpDevice(uri, uri_text, hand);
  if (uri.scheme == "serial") return openSerialDevice(uri, uri_text);
  throw InputError(fmt::format("device URI \"{}\": unknown scheme \"{}\"; accepted: {}", uri_text, uri.scheme, kAccepted));
}

std::optional<DeviceLimits> limitsWithoutOpening(std::string_view uri) {
  const DeviceUri parsed = parseDeviceUri(uri);
  if (parsed.scheme == "sim" && parsed.target == "pen") return simulatedPenParams(parsed).limits;
  if (parsed.scheme == "sim" && parsed.target == "planar") return planarPenLimits(simulatedPlanarParams(parsed).spec);
  return std::nullopt;
}

std::string deviceUriHelp() {
  std::string text = fmt::format("Device URIs: {}.\nsim://pen keys:\n", kAccepted);
  SimulatedPenParams defaults;
  for (const auto& k : kSimKeys) {
    text += fmt::format("  {:<24} {} in [{}, {}], default {}\n", k.key, k.help, k.min, k.max, *k.field(defaults));
  }
  text += udpDeviceHelp();
  text += serialDeviceHelp();
  return text;
}

}  // namespace hattr::device
