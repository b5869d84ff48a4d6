#include "support/test_support.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "support/host_stalls.hpp"

namespace hattr::test {

std::string inputErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

TempDir::TempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "hattr-test-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::optional<std::filesystem::path> svc2004Folder() {
  const char* source = std::getenv("HATTR_SOURCE_DIR");
  const std::filesystem::path root = source ? source : ".";
  const auto folder = root / ".." / "shared" / "data" / "svc2004-task2";
  if (!std::filesystem::is_directory(folder)) return std::nullopt;
  return folder;
}

namespace {

// The build's list of built files: one NAME=path a line.
std::map<std::string, std::string> readBuiltFiles() {
  const char* list = std::getenv("HATTR_BUILT_FILES");
  if (list == nullptr) {
    std::fputs("HATTR_BUILT_FILES is not set: run this test through ctest, which points it at the build's "
               "list of built files (tests/CMakeLists.txt)\n", stderr);
    std::exit(2);
  }
  std::ifstream in(list);
  if (!in) {
    std::fprintf(stderr, "HATTR_BUILT_FILES names %s, which cannot be read: build the tests again\n", list);
    std::exit(2);
  }
  std::map<std::string, std::string> files;
  std::string line;
  while (std::getline(in, line)) {
    const auto equals = line.find('=');
    if (equals != std::string::npos) files[line.substr(0, equals)] = line.substr(equals + 1);
  }
  return files;
}

}  // namespace

const char* builtFile(const std::string& name) {
  static const std::map<std::string, std::string> files = readBuiltFiles();
  const auto found = files.find(name);
  if (found == files.end()) {
    std::fprintf(stderr, "%s is not in the build's list of built files (%s): expected one of the names "
                 "tests/CMakeLists.txt writes\n", name.c_str(), std::getenv("HATTR_BUILT_FILES"));
    std::exit(2);
  }
  return found->second.c_str();
}

void writeText(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
}

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

HapticProfile randomProfile(std::mt19937_64& rng, std::size_t samples, RawChannels raw) {
  ProfileMetadata meta{.subject = "S07", .skill = "na", .device = "sim://pen?mass_kg=0.045",
                       .source = "test", .created_utc = "2026-11-21T21:00:00Z", .nominal_rate_hz = 1000.0,
                       .extra = {{"mode", "alpha"}, {"trial", "3"}, {"note", "a: b, c"}}};
  HapticProfile profile(meta, raw);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> scale(-12, 0);
  // Values spread over many magnitudes (within what a profile file may hold: 1 m, 1 kN),
  // plus subnormals and signed zeros.
  const auto value = [&]() {
    const int pick = static_cast<int>(rng() % 20);
    if (pick == 0) return std::numeric_limits<double>::denorm_min() * static_cast<double>(rng() % 1000);
    if (pick == 1) return -0.0;
    return unit(rng) * std::pow(10.0, scale(rng));
  };
  double t = unit(rng);
  for (std::size_t i = 0; i < samples; ++i) {
    Sample s;
    t = std::nextafter(t + std::abs(unit(rng)) * 1e-3, 1e9);
    s.t_s = t;
    s.p_WT = Vec3(value(), value(), value());
    s.v_WT = Vec3(value(), value(), value());
    s.f_user_W = Vec3(value(), value(), value());
    s.f_cmd_W = Vec3(value(), value(), value());
    s.f_guide_W = Vec3(value(), value(), value());
    s.in_contact = rng() % 2 == 0;
    s.pen_down = rng() % 3 != 0;
    if (raw.pressure) s.pressure_raw = static_cast<double>(rng() % 1024);
    if (raw.tilt) {
      s.tilt_azimuth_rad = value();
      s.tilt_altitude_rad = value();
    }
    profile.append(s);
  }
  return profile;
}

std::uint64_t testSeed(std::uint64_t default_seed) {
  const char* env = std::getenv("HATTR_TEST_SEED");
  return env ? std::strtoull(env, nullptr, 10) : default_seed;
}

}  // namespace hattr::test

// ---- real-time attempts (host_stalls.hpp) ----

namespace hattr::test {

bool passesUnlessTheHostStalls(const RealTimeAttempt& attempt, int tries) {
  std::string last_failures;
  std::uint64_t last_stalls = 0;
  for (int k = 1; k <= tries; ++k) {
    // Capture this attempt's failures instead of reporting them.
    ::testing::TestPartResultArray results;
    std::uint64_t stalls = 0;
    {
      ::testing::ScopedFakeTestPartResultReporter capture(
          ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
      attempt(stalls);
    }
    std::string failures;
    for (int i = 0; i < results.size(); ++i) {
      const auto& r = results.GetTestPartResult(i);
      if (!r.failed()) continue;
      failures += fmt::format("{}:{}: {}\n", r.file_name() ? r.file_name() : "?", r.line_number(), r.message());
    }
    if (failures.empty()) return true;
    // A failure no stall explains is the test's own: report it as it was.
    if (stalls == 0) {
      for (int i = 0; i < results.size(); ++i) {
        const auto& r = results.GetTestPartResult(i);
        if (r.failed()) ADD_FAILURE_AT(r.file_name() ? r.file_name() : "?", r.line_number()) << r.message();
      }
      return false;
    }
    std::printf("attempt %d of %d: the host stalled the loops %llu times; it failed with:\n%s", k, tries,
                static_cast<unsigned long long>(stalls), failures.c_str());
    last_failures = std::move(failures);
    last_stalls = stalls;
  }
  [&] {
    GTEST_SKIP() << "the host stalled every attempt (" << last_stalls << " stalls in the last), so its real-time "
                 << "expectations could not be checked; the last attempt's failures:\n" << last_failures;
  }();
  return false;
}

HostStallWatch::HostStallWatch(std::uint64_t& host_stalls, std::chrono::milliseconds gap) : host_stalls_(host_stalls) {
  thread_ = std::thread([this, gap] {
    constexpr auto kNap = std::chrono::milliseconds(1);
    auto last = std::chrono::steady_clock::now();
    while (!stop_.load()) {
      std::this_thread::sleep_for(kNap);
      const auto now = std::chrono::steady_clock::now();
      if (now - last > kNap + gap) stalls_.fetch_add(1);
      last = now;
    }
  });
}

HostStallWatch::~HostStallWatch() {
  stop_.store(true);
  thread_.join();
  host_stalls_ += stalls_.load();
}

}  // namespace hattr::test
