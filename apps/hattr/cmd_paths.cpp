// hattr paths: where this hattr finds what it reads at run time (the prefix it is installed in,
// the glyphs and simulation data, the plugins, the open pen's firmware), for a lab checking an
// install. The folders are found relative to the program (hattr/core/install_layout.hpp).

#include <cstdlib>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "hattr/core/install_layout.hpp"
#include "hattr/device/plugin_device.hpp"
#include "hattr/sim/data_dir.hpp"

namespace hattr::cli {
namespace {

void runPaths(bool json) {
  const auto share = findShareDir();
  const char* env = std::getenv("HATTR_DATA_DIR");
  const auto firmware = share ? *share / "firmware" / "openpen-atmega328p.elf" : std::filesystem::path{};
  nlohmann::json out{{"program", codeLocation().string()},
                     {"share_dir", share ? share->string() : ""},
                     {"data_dir", sim::defaultDataDir().string()},
                     {"data_dir_from", env != nullptr && *env != '\0' ? "HATTR_DATA_DIR" : "prefix"},
                     {"plugin_search_path", device::pluginSearchPath()},
                     {"firmware", std::filesystem::is_regular_file(firmware) ? firmware.string() : ""}};
  if (json) {
    printJson(out);
    return;
  }
  std::cout << fmt::format("program      {}\nshare        {}\ndata         {} (from {})\nplugins      {}\nfirmware     {}\n",
                           out["program"].get<std::string>(), share ? share->string() : "(none found)",
                           out["data_dir"].get<std::string>(), out["data_dir_from"].get<std::string>(),
                           fmt::join(device::pluginSearchPath(), ":"),
                           out["firmware"].get<std::string>().empty() ? "(not installed)" : firmware.string());
}

}  // namespace

void registerPathsCommand(CLI::App& app) {
  auto* paths = app.add_subcommand("paths", "Where this hattr finds its data, plugins and firmware (an install's check)");
  auto json = std::make_shared<bool>(false);
  paths->add_flag("--json", *json, "Print the paths as JSON");
  paths->callback([json] { runPaths(*json); });
}

}  // namespace hattr::cli
