// hattr demo: the main job as it stands. Today: import real pen recordings and summarize
// their haptic profiles. The simulated study replaces this as the simulation lands.

#include <filesystem>
#include <iostream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/io/tablet_import.hpp"

namespace hattr::cli {
namespace {

struct DemoOptions {
  std::string data_dir = "../shared/data/svc2004-task2";
  std::string out_dir = "demo-out";
};

void runDemo(const DemoOptions& opt) {
  namespace fs = std::filesystem;
  HATTR_THROW_UNLESS(fs::is_directory(opt.data_dir),
                     "--data: expected a folder of SVC2004 .TXT files, got \"{}\" (not a folder)", opt.data_dir);
  fs::create_directories(opt.out_dir);
  const io::TabletCalibration calibration = io::svc2004Calibration();
  std::cout << fmt::format("{:<12} {:>8} {:>9} {:>10} {:>12}\n", "recording", "samples", "pen down",
                           "duration", "peak |f|");
  // A writer's genuine signatures: their haptic profiles side by side.
  for (int signature = 1; signature <= 5; ++signature) {
    const std::string name = fmt::format("U1S{}", signature);
    const HapticProfile profile = io::importSvc2004(fs::path(opt.data_dir) / (name + ".TXT"), calibration);
    io::writeProfileCsv(profile, fs::path(opt.out_dir) / (name + ".csv"), io::Overwrite::kReplace);
    std::cout << fmt::format("{:<12} {:>8} {:>9} {:>8.2f} s {:>10.2f} N\n", name, profile.size(),
                             profile.penDownCount(), profile.duration_s(),
                             profile.range(Channel::kForceMagnitude).max);
  }
  std::cout << fmt::format("\nprofiles written to {}/ (inspect one: hattr profile info {}/U1S1.csv)\n",
                           opt.out_dir, opt.out_dir);
}

}  // namespace

void registerDemoCommand(CLI::App& app) {
  auto opt = std::make_shared<DemoOptions>();
  auto* demo = app.add_subcommand("demo", "Run the main job as it stands: import real pen data as haptic profiles");
  demo->add_option("--data", opt->data_dir, "Folder with SVC2004 task 2 .TXT files")->capture_default_str();
  demo->add_option("--out", opt->out_dir, "Where to write the profiles")->capture_default_str();
  demo->callback([opt] { runDemo(*opt); });
}

}  // namespace hattr::cli
