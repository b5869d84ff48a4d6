#pragma once
// Helpers shared by hattr's tests: temporary folders, the shared data set, seeded
// random profiles.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <string>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::test {

/// A fresh temporary folder, removed with everything in it when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

/// The SVC2004 task 2 folder beside the project (../shared/data/svc2004-task2), or
/// nullopt when it is absent (tests then skip with a message).
std::optional<std::filesystem::path> svc2004Folder();

/// A file the build made (the hattr CLI, a plugin) by its name in the list the build writes
/// beside the tests (tests/CMakeLists.txt: HATTR_CLI, HATTR_SIM_PLUGIN, ...; ctest passes the
/// list's path in HATTR_BUILT_FILES). Read at run time rather than compiled in, so a clone in
/// another folder compiles the same objects and the compiler cache reuses them. A missing list
/// or name ends the program with exit code 2 and what is missing.
const char* builtFile(const std::string& name);

/// Not-a-number and infinity, for tests that feed them in or expect them out.
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// The message of the InputError `f` throws, or "(no InputError)" when it throws none.
std::string inputErrorOf(const std::function<void()>& f);

/// Writes `text` to `file`.
void writeText(const std::filesystem::path& file, const std::string& text);
std::string readText(const std::filesystem::path& file);

/// A random profile with awkward floats (tiny, huge, negative, subnormal) for round trips.
HapticProfile randomProfile(std::mt19937_64& rng, std::size_t samples, RawChannels raw);

/// The seed of a randomized test: HATTR_TEST_SEED if set, else a fixed default. Printed
/// by the test on failure.
std::uint64_t testSeed(std::uint64_t default_seed);

}  // namespace hattr::test
