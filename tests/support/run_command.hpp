#pragma once
// Runs a command line through the shell for the CLI tests: its exit code and its output, kept in
// files in the test's folder.

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "support/test_support.hpp"

extern char** environ;

namespace hattr::test {

struct RunResult {
  int exit_code;
  std::string out;
  std::string err;
};

/// `program args` (shell-quoted by the caller); stdout and stderr in `dir`/TAG.out and TAG.err.
inline RunResult runCommand(const TempDir& dir, const std::string& program, const std::string& args,
                            const std::string& tag = "run") {
  const auto out = dir / (tag + ".out");
  const auto err = dir / (tag + ".err");
  const std::string command = program + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, readText(out), readText(err)};
}

/// Open MPI's launcher, which the CLI tests start for real (scripts/install-deps installs it);
/// empty when it is missing.
inline std::string mpirun() {
  for (const char* candidate : {"/usr/bin/mpirun", "/usr/local/bin/mpirun"}) {
    if (std::filesystem::exists(candidate)) return candidate;
  }
  return {};
}

/// mpirun's settings for this machine: it runs as root here (Open MPI refuses that unless
/// told), and LeakSanitizer would report what Open MPI's own library keeps until exit.
inline const std::string kMpiEnvironment = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
                                           "OMPI_MCA_rmaps_base_oversubscribe=1 ASAN_OPTIONS=detect_leaks=0 ";

/// The CLI the tests run, looked up when a test runs (listing the tests needs no build list).
inline std::string hattrCli() { return builtFile("HATTR_CLI"); }

/// `hattr args`, as runCommand runs it.
inline RunResult runHattr(const TempDir& dir, const std::string& args, const std::string& tag = "run") {
  return runCommand(dir, hattrCli(), args, tag);
}

/// Starts `args` (args[0] the program) in the background, its stdout discarded and its stderr
/// appended to `err` (or inherited when empty); returns its process id (exitStatus waits).
inline pid_t spawnProcess(std::vector<std::string> args, const std::filesystem::path& err = {}) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  const std::string err_file = err.string();
  if (!err.empty()) {
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_file.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  }
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("posix_spawn failed for " + args[0]);
  return pid;
}

/// Waits for a spawned process: its exit code, or minus the signal that ended it.
inline int exitStatus(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

}  // namespace hattr::test
