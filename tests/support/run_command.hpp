#pragma once
// Runs a command line through the shell for the CLI tests: its exit code and its output, kept in
// files in the test's folder.

#include <sys/wait.h>

#include <cstdlib>
#include <string>

#include "support/test_support.hpp"

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

}  // namespace hattr::test
