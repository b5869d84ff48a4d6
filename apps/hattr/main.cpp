// hattr: the command-line tool. Thin: parses arguments and calls the library.
// Exit codes: 0 ok, 1 runtime failure, 2 bad input or usage; errors go to stderr.

#include <iostream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/version.hpp"

int main(int argc, char** argv) {
  using namespace hattr::cli;
  CLI::App app{"hattr: motor skill training with haptic attributes.\n"
               "Record an expert's haptic profile, train against it, analyse the results."};
  app.set_version_flag("--version", fmt::format("hattr {}", hattr::kVersion));
  app.require_subcommand(1);
  registerProfileCommands(app);
  registerImportCommands(app);
  registerServoCheckCommand(app);
  registerDevicesCommands(app);
  registerMentorCommands(app);
  registerWorldCommands(app);
  registerRecordTrainCommands(app);
  registerStudyCommands(app);
  registerAnalysisCommands(app);
  registerSimCommands(app);
  registerDemoCommand(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kOk : kBadInput;
  } catch (const hattr::InputError& e) {
    std::cerr << "hattr: error: " << e.what() << '\n';
    return kBadInput;
  } catch (const std::exception& e) {
    std::cerr << "hattr: failed: " << e.what() << '\n';
    return kRuntimeFailure;
  }
  return kOk;
}
