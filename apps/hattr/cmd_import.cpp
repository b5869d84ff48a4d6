// hattr import svc2004|susig FILE -o OUT.csv

#include <iostream>

#include "cli_common.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/io/tablet_import.hpp"

namespace hattr::cli {
namespace {

enum class TabletFormat { kSvc2004, kSusig };

struct ImportOptions {
  std::string input;
  std::string output;
  std::string calibration;
  std::string subject;
  std::string skill;
  bool json = false;
  bool force = false;
};

void runImport(TabletFormat format, const ImportOptions& opt) {
  checkOutputFiles({opt.output}, opt.force);
  const io::TabletCalibration defaults =
      format == TabletFormat::kSvc2004 ? io::svc2004Calibration() : io::susigCalibration();
  const io::TabletCalibration calibration =
      opt.calibration.empty() ? defaults : io::loadCalibration(opt.calibration, defaults);
  HapticProfile profile = format == TabletFormat::kSvc2004 ? io::importSvc2004(opt.input, calibration)
                                                           : io::importSusig(opt.input, calibration);
  if (!opt.subject.empty()) profile.metadata().subject = opt.subject;
  if (!opt.skill.empty()) profile.metadata().skill = opt.skill;
  io::writeProfileCsv(profile, opt.output, opt.force ? hattr::Overwrite::kReplace : hattr::Overwrite::kRefuse);

  if (opt.json) {
    nlohmann::json json = ops::profileSummaryJson(profile);
    json["file"] = opt.output;
    json["input"] = opt.input;
    printJson(json);
  } else {
    std::cout << "imported " << opt.input << " -> " << opt.output << '\n' << profileSummaryText(profile);
  }
}

void addImportSubcommand(CLI::App& import, TabletFormat format, const char* name, const char* help) {
  auto opt = std::make_shared<ImportOptions>();
  auto* cmd = import.add_subcommand(name, help);
  cmd->add_option("FILE", opt->input, "Recording to import")->required();
  cmd->add_option("-o,--output", opt->output, "Haptic-profile CSV to write")->required();
  cmd->add_option("--calibration", opt->calibration,
                  "JSON file overriding calibration fields (see docs/file-formats.md)");
  cmd->add_option("--subject", opt->subject, "Subject recorded in the metadata");
  cmd->add_option("--skill", opt->skill, "Skill or character recorded in the metadata");
  cmd->add_flag("--json", opt->json, "Print the imported profile's summary as JSON (as `profile info --json`)");
  cmd->add_flag("--force", opt->force, "Replace the output file if it exists");
  cmd->callback([opt, format] { runImport(format, *opt); });
}

}  // namespace

void registerImportCommands(CLI::App& app) {
  auto* import = app.add_subcommand("import", "Import real pen-tablet recordings as haptic profiles (SI units)");
  import->require_subcommand(1);
  addImportSubcommand(*import, TabletFormat::kSvc2004, "svc2004",
                      "SVC2004 .TXT: N, then lines X Y T button azimuth altitude pressure");
  addImportSubcommand(*import, TabletFormat::kSusig, "susig",
                      "SUSIG: header X, Y, TStamp, Pres., EndPts and DataSize: N");
}

}  // namespace hattr::cli
