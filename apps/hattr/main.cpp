// hattr: the command-line tool. Thin: parses arguments and calls the library.
// Exit codes: 0 ok, 1 runtime failure, 2 bad input or usage; errors go to stderr.

#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/version.hpp"

namespace {

/// Edit distance (insertions, deletions, substitutions, adjacent swaps) between two words.
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

/// The first word of the command line that should name a command but names none, with the
/// closest command's name when one is close: "unknown command "stdy"; did you mean "study"?".
/// Empty when the command words are all known (CLI11 then reports anything else).
std::string unknownCommandMessage(const CLI::App& app, int argc, char** argv) {
  const CLI::App* level = &app;
  std::string path = "hattr";
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') return "";  // options: CLI11's own messages
    const auto commands = level->get_subcommands([](const CLI::App*) { return true; });
    const auto named = std::find_if(commands.begin(), commands.end(), [&](const CLI::App* c) { return c->check_name(word); });
    if (named != commands.end()) {
      level = *named;
      path += " " + (*named)->get_name();
      continue;
    }
    // A word that may be a positional argument here is not a command.
    const bool takes_positional =
        !level->get_options([](const CLI::Option* o) { return o->get_positional(); }).empty();
    if (commands.empty() || takes_positional) return "";
    // The closest command, if it is close enough to be a slip of the keyboard.
    std::string best;
    std::size_t best_distance = word.size();
    std::string names;
    for (const CLI::App* c : commands) {
      names += (names.empty() ? "" : ", ") + c->get_name();
      for (const std::string& name : [&] {
             std::vector<std::string> all{c->get_name()};
             all.insert(all.end(), c->get_aliases().begin(), c->get_aliases().end());
             return all;
           }()) {
        const std::size_t distance = editDistance(word, name);
        if (distance < best_distance) {
          best_distance = distance;
          best = c->get_name();
        }
      }
    }
    const bool close = !best.empty() && best_distance <= std::max<std::size_t>(2, word.size() / 3);
    return fmt::format("unknown command \"{}\" after \"{}\"{} (commands: {}; `{} --help` says more)", word, path,
                       close ? fmt::format(": did you mean \"{} {}\"?", path, best) : "", names, path);
  }
  return "";
}

}  // namespace

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
  registerLearnerCommands(app);
  registerAnalysisCommands(app);
  registerLmmCommand(app);
  registerSimCommands(app);
  registerDemoCommand(app);
  registerPathsCommand(app);
  registerLibraryCommands(app);

  if (const std::string unknown = unknownCommandMessage(app, argc, argv); !unknown.empty()) {
    std::cerr << "hattr: error: " << unknown << '\n';
    return kBadInput;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kOk : kBadInput;
  } catch (const hattr::InputError& e) {
    std::cerr << "hattr: error: " << e.what() << '\n';
    return kBadInput;
  } catch (const ExitQuietly& e) {
    return e.code;
  } catch (const std::exception& e) {
    std::cerr << "hattr: failed: " << e.what() << '\n';
    return kRuntimeFailure;
  }
  return kOk;
}
