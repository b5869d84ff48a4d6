#pragma once
// Shared pieces of the hattr command-line tool: exit codes, JSON summaries, output.

#include <chrono>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/servo/loop_verdict.hpp"

namespace hattr::cli {

/// Exit codes of every hattr command.
enum ExitCode : int { kOk = 0, kRuntimeFailure = 1, kBadInput = 2 };

/// Thrown by a command whose failure was already told (by it, or by another MPI rank):
/// main() returns `code` and prints nothing.
struct ExitQuietly {
  int code;
};

/// A profile's summary for people (its JSON: ops::profileSummaryJson).
std::string profileSummaryText(const HapticProfile& profile);

/// Prints JSON (indented) to stdout.
void printJson(const nlohmann::json& json);

/// A loop run's verdicts (servo::judgeLoop; their JSON: ops::verdictsJson) for people: one
/// text line a figure ("PASS  faults  0  (PASS 0, else FAIL ...)") ending with the overall verdict.
std::string verdictsText(const servo::LoopJudgement& judgement);

void registerProfileCommands(CLI::App& app);
void registerImportCommands(CLI::App& app);
void registerDemoCommand(CLI::App& app);
void registerPathsCommand(CLI::App& app);
void registerLibraryCommands(CLI::App& app);
void registerServoCheckCommand(CLI::App& app);
void registerWorldCommands(CLI::App& app);
void registerRecordTrainCommands(CLI::App& app);
void registerStudyCommands(CLI::App& app);
/// `hattr learner plan | list | progress` (cmd_learner.cpp).
void registerLearnerCommands(CLI::App& app);
void registerAnalysisCommands(CLI::App& app);
void registerLmmCommand(CLI::App& app);
void registerSimCommands(CLI::App& app);
/// `hattr sim power` and `hattr sim power merge` (cmd_sim_power.cpp).
void registerPowerCommands(CLI::App& sim);
/// `plan` under `sim`: the smallest design that reaches a target power (cmd_sim_plan.cpp).
void registerPlanCommand(CLI::App& sim);
/// hattr sim compare-hypotheses (cmd_sim_hypotheses.cpp).
void registerHypothesisCommands(CLI::App& sim);
/// hattr sim compare-strategies (cmd_sim_strategies.cpp).
void registerStrategyComparisonCommand(CLI::App& sim);
void registerDevicesCommands(CLI::App& app);
void registerMentorCommands(CLI::App& app);
/// `serve` and `keygen` under the `devices` (alias `device`) command: the network device server.
void registerDeviceServeCommands(CLI::App& devices);

/// "6,10,20" as numbers; InputError naming `option` for anything else.
std::vector<int> commaSeparatedInts(const std::string& text, std::string_view option);
/// "i/N" (0 <= i < N) as {i, N}, {0, 1} when empty; InputError naming `option` otherwise.
std::pair<int, int> shardOf(const std::string& text, std::string_view option = "--shard");

/// Before any work: refuses (InputError, exit 2) every output file that exists unless
/// `force` ("...: already exists; add --force to replace it"), is a folder, or whose folder
/// is missing or not writable, so a command never works (or records) and then cannot write.
void checkOutputFiles(const std::vector<std::filesystem::path>& files, bool force);
/// The same for an output folder and the files and folders a command writes in it: `dir`
/// must be a writable folder, or not exist yet under a writable one (the writer creates it);
/// each of `names` inside it must not exist unless `force`. Creates nothing.
void checkOutputFolder(const std::filesystem::path& dir, const std::vector<std::string>& names, bool force);
/// Writes a recording; if that fails (a full disk, a folder gone), keeps it beside the
/// temporary folder's copy instead and throws hattr::Error naming where it is: a recording
/// is never lost.
void writeRecording(const HapticProfile& profile, const std::filesystem::path& file, bool force);

/// A progress line for long commands, on stderr and only when stderr is a terminal: scripts,
/// pipes and CI logs see nothing. "label [#####.....] done/total unit, about N s left" (just
/// the label while the total is 0), redrawn at most ten times a second; a new stage is drawn
/// at once; finish() (or the destructor) clears the line.
class Progress {
 public:
  Progress(std::string label, double total, std::string unit);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// `done` of the total so far; `label` replaces the label when not empty.
  void update(double done, const std::string& label = {});
  /// A new stage: its label and total (0: no count), drawn at once; the time-left estimate
  /// starts again.
  void stage(const std::string& label, double total);
  /// Clears the line (nothing was drawn when stderr is not a terminal).
  void finish();
  [[nodiscard]] const std::string& label() const noexcept { return label_; }
  /// Whether progress is drawn: stderr is a terminal and TERM is not "dumb".
  [[nodiscard]] static bool onTerminal();

 private:
  std::string label_;
  double total_;
  std::string unit_;
  bool shown_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_draw_{};
};

/// An in-silico study's progress callback drawing on `progress`: "PREFIX: running the study",
/// "PREFIX: scoring recall trials", "PREFIX: writing the report".
std::function<void(std::string_view, int, int)> stageProgress(Progress& progress, std::string prefix);

/// The world configuration in `file`, or the defaults when `file` is empty.
render::WorldConfig worldConfigOrDefault(const std::string& file);

}  // namespace hattr::cli
