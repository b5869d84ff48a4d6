// hattr world defaults|check: the paper/world configuration.

#include <iostream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/render/world_config.hpp"

namespace hattr::cli {

render::WorldConfig worldConfigOrDefault(const std::string& file) {
  return file.empty() ? render::WorldConfig{} : render::loadWorldConfig(file);
}

namespace {

/// Clamps the paper to the passive bounds of the device `device_uri` at `rate_hz` (a sim://
/// pen's declared limits, any other device's once opened: its one open here); one line per change.
std::vector<std::string> clampWorldToDevice(render::WorldConfig& world, const std::string& device_uri, double rate_hz) {
  const std::optional<DeviceLimits> declared = device::limitsWithoutOpening(device_uri);
  return render::clampToDevice(world.paper, declared ? *declared : device::openDevice(device_uri, nullptr)->limits(),
                               rate_hz);
}

struct WorldCheckOptions {
  std::string file;
  std::string device = "sim://pen";
  double rate_hz = 1000.0;
  bool json = false;
};

void runWorldCheck(const WorldCheckOptions& opt) {
  render::WorldConfig world = render::loadWorldConfig(opt.file);
  const auto clamps = clampWorldToDevice(world, opt.device, opt.rate_hz);
  const render::HeightField relief = render::buildRelief(world.relief);
  if (opt.json) {
    printJson({{"file", opt.file},
               {"device", opt.device},
               {"rate_hz", opt.rate_hz},
               {"clamps", clamps},
               {"relief_vertices", {relief.nx(), relief.ny()}},
               {"relief_spacing_m", relief.flat() ? 0.0 : relief.spacing_m()}});
    return;
  }
  std::cout << fmt::format("{}: valid; relief {}×{} vertices\n", opt.file, relief.nx(), relief.ny());
  if (clamps.empty()) std::cout << fmt::format("renders passively on {} at {} Hz as written\n", opt.device, opt.rate_hz);
  for (const auto& c : clamps) std::cout << "clamped: " << c << '\n';
}

}  // namespace

void registerWorldCommands(CLI::App& app) {
  auto* world = app.add_subcommand("world", "The paper/world configuration (see docs/rendering.md)");
  world->require_subcommand(1);
  auto* defaults = world->add_subcommand("defaults", "Print the default configuration as JSON (a starting point to edit)");
  defaults->callback([] { std::cout << render::defaultWorldConfigJson() << '\n'; });

  auto opt = std::make_shared<WorldCheckOptions>();
  auto* check = world->add_subcommand("check", "Validate a configuration and show what the device's passivity bounds clamp");
  check->add_option("FILE", opt->file, "World configuration JSON")->required();
  check->add_option("--device", opt->device, "Device URI")->capture_default_str();
  check->add_option("--rate", opt->rate_hz, "Servo rate [Hz]")->check(CLI::Range(1.0, 10000.0))->capture_default_str();
  check->add_flag("--json", opt->json, "Print JSON: clamps (list of strings), relief_vertices, relief_spacing_m");
  check->callback([opt] { runWorldCheck(*opt); });
}

}  // namespace hattr::cli
