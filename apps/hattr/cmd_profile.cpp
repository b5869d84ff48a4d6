// hattr profile info|convert

#include <iostream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/io/profile_csv.hpp"

namespace hattr::cli {
namespace {

struct ProfileInfoOptions {
  std::string file;
  bool json = false;
};

struct ProfileConvertOptions {
  std::string input;
  std::string output;
  double scale_force = 1.0;
  bool centre = false;
  bool force = false;
};

/// The profile with every force scaled by `factor` (positions, times, pressure and tilt kept)
/// and, with `centre`, its writing moved to the paper's centre (centreOnPaper); each change
/// noted in its metadata (force_scaled_by, placed_shift_m).
HapticProfile converted(const HapticProfile& profile, double factor, bool centre) {
  std::vector<Sample> samples = profile.samples();
  ProfileMetadata metadata = profile.metadata();
  if (factor != 1.0) {
    for (Sample& s : samples) {
      s.f_user_W *= factor;
      s.f_cmd_W *= factor;
      s.f_guide_W *= factor;
    }
    metadata.extra["force_scaled_by"] = fmt::format("{}", factor);
  }
  if (centre) {
    const Vec3 shift = centreOnPaper(samples);
    metadata.extra["placed_shift_m"] = fmt::format("{} {}", shift.x(), shift.y());
  }
  return HapticProfile::fromSamples(std::move(metadata), profile.rawChannels(), std::move(samples), false);
}

void runProfileInfo(const ProfileInfoOptions& opt) {
  const HapticProfile profile = io::readProfileCsv(opt.file);
  if (opt.json) {
    nlohmann::json json = ops::profileSummaryJson(profile);
    json["file"] = opt.file;
    printJson(json);
  } else {
    std::cout << "file        " << opt.file << '\n' << profileSummaryText(profile);
  }
}

void runProfileConvert(const ProfileConvertOptions& opt) {
  checkOutputFiles({opt.output}, opt.force);
  HapticProfile profile = io::readProfileCsv(opt.input);
  if (opt.scale_force != 1.0 || opt.centre) profile = converted(profile, opt.scale_force, opt.centre);
  io::writeProfileCsv(profile, opt.output, opt.force ? hattr::Overwrite::kReplace : hattr::Overwrite::kRefuse);
  std::cout << "wrote " << opt.output << " (" << profile.size() << " samples, SI units"
            << (opt.scale_force != 1.0 ? fmt::format(", forces scaled by {}", opt.scale_force) : std::string())
            << (opt.centre ? fmt::format(", centred on the paper: placed_shift_m {}", profile.metadata().extra.at("placed_shift_m"))
                           : std::string())
            << ")\n";
}

}  // namespace

void registerProfileCommands(CLI::App& app) {
  auto* profile = app.add_subcommand("profile", "Inspect and convert haptic-profile files");
  profile->require_subcommand(1);

  auto info_opt = std::make_shared<ProfileInfoOptions>();
  auto* info = profile->add_subcommand("info", "Samples, duration, rate, channel ranges and metadata of a profile");
  info->add_option("FILE", info_opt->file, "Haptic-profile CSV file")->required();
  info->add_flag("--json", info_opt->json,
                 "Print JSON: samples, pen_down_samples, duration_s, rate_hz, nominal_rate_hz, "
                 "channels {name: {unit, min, max}}, metadata");
  info->callback([info_opt] { runProfileInfo(*info_opt); });

  auto convert_opt = std::make_shared<ProfileConvertOptions>();
  auto* convert = profile->add_subcommand(
      "convert", "Read a profile (mm/ms columns, missing velocity allowed) and write it in canonical SI form");
  convert->add_option("IN", convert_opt->input, "Input profile CSV")->required();
  convert->add_option("OUT", convert_opt->output, "Output profile CSV")->required();
  convert->add_option("--scale-force", convert_opt->scale_force,
                      "Multiply every force by this factor (positions and times kept), e.g. to bring an expert "
                      "within a device's continuous force (noted in the metadata as force_scaled_by)")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  convert->add_flag("--centre", convert_opt->centre,
                    "Move the writing (the centre of its pen-down points' box) to the paper's centre, the origin, "
                    "e.g. to bring tablet data into a device's workspace (noted in the metadata as placed_shift_m)");
  convert->add_flag("--force", convert_opt->force, "Replace OUT if it exists");
  convert->callback([convert_opt] { runProfileConvert(*convert_opt); });
}

}  // namespace hattr::cli
