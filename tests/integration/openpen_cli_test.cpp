// The open pen end to end through the CLI: `hattr record` and `hattr train` on serial://PTY, the
// unmodified firmware under the emulator in lockstep, against the same trials on sim://planar
// (the same plant with ideal electronics); and two lockstep runs giving the same trace.

#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "hattr/io/profile_csv.hpp"
#include "integration/openpen_test_support.hpp"
#include "support/run_command.hpp"

namespace hattr::test {
namespace {

/// How far two recordings of one trial lie apart, sample by sample.
struct Apart {
  double position_rms_m = 0.0;
  double force_rms_N = 0.0;     ///< the user's force on the paper (in plane and normal)
  double guidance_rms_N = 0.0;  ///< the guidance force
  double guidance_size_N = 0.0; ///< the RMS guidance force of the simulated run (for scale)
  std::size_t samples = 0;
};

Apart apart(const HapticProfile& a, const HapticProfile& b) {
  Apart out;
  out.samples = std::min(a.size(), b.size());
  double p = 0.0, f = 0.0, g = 0.0, size = 0.0;
  for (std::size_t i = 0; i < out.samples; ++i) {
    const Sample& x = a[i];
    const Sample& y = b[i];
    p += (x.p_WT - y.p_WT).head<2>().squaredNorm();
    f += (x.f_user_W - y.f_user_W).squaredNorm();
    g += (x.f_guide_W - y.f_guide_W).head<2>().squaredNorm();
    size += y.f_guide_W.head<2>().squaredNorm();
  }
  const double n = static_cast<double>(std::max<std::size_t>(out.samples, 1));
  out.position_rms_m = std::sqrt(p / n);
  out.force_rms_N = std::sqrt(f / n);
  out.guidance_rms_N = std::sqrt(g / n);
  out.guidance_size_N = std::sqrt(size / n);
  return out;
}

std::string fileText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The trial `args` (a `hattr record` or `hattr train` command line without --device) on the
/// emulated firmware, the hand writing `hand`; the plant's trace in `trace`.
HapticProfile onTheFirmware(const TempDir& dir, const std::string& args, const std::filesystem::path& hand,
                            const std::filesystem::path& out, const std::filesystem::path& trace) {
  // `hattr record` and `train` open the pen once, for the trial, and read its limits from it: the
  // emulator exits after one hang-up, so a second open would find no pen (issue 63).
  PenEmulator emulator(dir, {"--hand", hand.string(), "--hangups", "1", "--trace", trace.string()});
  EXPECT_FALSE(emulator.pty().empty());
  const RunResult r = runHattr(dir, fmt::format("{} --device 'serial://{}?lockstep=1' -o {} --force", args,
                                                emulator.pty(), out.string()),
                               out.stem().string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(emulator.process().wait(), 0) << fileText(dir / "emulator.err");
  return io::readProfileCsv(out);
}

HapticProfile onTheSimulatedPlanarPen(const TempDir& dir, const std::string& args, const std::filesystem::path& out) {
  const RunResult r = runHattr(dir, fmt::format("{} --device sim://planar -o {} --force", args, out.string()), out.stem().string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return io::readProfileCsv(out);
}

class OpenPenCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (penEmulator().empty() || penFirmware().empty()) GTEST_SKIP() << "the open pen's firmware or emulator was not built";
    // The expert's script (the Tamil ந), recorded on the simulated planar pen as the reference; a
    // trainee who writes it 2 mm to the right and 1 mm nearer, pressing half as hard (so the
    // friction it feels, which ALPHA compares in the plane, is half the expert's).
    ASSERT_EQ(runHattr(dir_, fmt::format("sim expert -o {} --script-out {}", (dir_ / "pen-expert.csv").string(),
                                         script().string()))
                  .exit_code,
              0);
    const HapticProfile expert = io::readProfileCsv(script());
    std::vector<Sample> moved = expert.samples();
    for (Sample& s : moved) {
      s.p_WT += Vec3(0.002, -0.001, 0.0);
      s.f_user_W *= 0.5;
    }
    io::writeProfileCsv(HapticProfile::fromSamples(expert.metadata(), expert.rawChannels(), moved, false), trainee_script());
  }
  std::filesystem::path script() const { return dir_ / "script.csv"; }
  std::filesystem::path trainee_script() const { return dir_ / "trainee-script.csv"; }

  TempDir dir_;
};

TEST_F(OpenPenCli, ARecordedTakeAndTrainingTrialsMatchTheSimulatedPlanarPen) {
  // The expert's take.
  const std::string record = fmt::format("record --hand {}", script().string());
  const HapticProfile take_fw = onTheFirmware(dir_, record, script(), dir_ / "take-firmware.csv", dir_ / "take-trace.csv");
  const HapticProfile take_sim = onTheSimulatedPlanarPen(dir_, record, dir_ / "take-sim.csv");
  const Apart take = apart(take_fw, take_sim);
  ASSERT_GT(take.samples, 4000u);
  std::cout << fmt::format("expert take: position RMS {:.3f} mm, force RMS {:.4f} N over {} samples\n",
                           take.position_rms_m * 1e3, take.force_rms_N, take.samples);
  EXPECT_LT(take.position_rms_m, 0.5e-3);
  EXPECT_LT(take.force_rms_N, 0.1);

  // PCONTROL and ALPHA, the trainee's hand, the take on the simulated planar pen as the reference.
  for (const char* mode : {"pcontrol", "alpha"}) {
    const std::string train = fmt::format("train --mode {} --reference {} --hand {}", mode, (dir_ / "take-sim.csv").string(),
                                          trainee_script().string());
    const HapticProfile fw =
        onTheFirmware(dir_, train, trainee_script(), dir_ / fmt::format("{}-firmware.csv", mode), dir_ / "trace.csv");
    const HapticProfile sim = onTheSimulatedPlanarPen(dir_, train, dir_ / fmt::format("{}-sim.csv", mode));
    const Apart a = apart(fw, sim);
    std::cout << fmt::format("{}: position RMS {:.3f} mm, force RMS {:.4f} N, guidance RMS {:.4f} N of {:.4f} N, {} samples\n",
                             mode, a.position_rms_m * 1e3, a.force_rms_N, a.guidance_rms_N, a.guidance_size_N, a.samples);
    EXPECT_GT(a.samples, 4000u) << mode;
    EXPECT_GT(a.guidance_size_N, 0.02) << mode << ": the guidance acted (ALPHA: its gain 0.5 on a friction difference of about 0.1 N)";
    EXPECT_LT(a.position_rms_m, 0.5e-3) << mode;
    EXPECT_LT(a.force_rms_N, 0.1) << mode;
    EXPECT_LT(a.guidance_rms_N, 0.25 * a.guidance_size_N) << mode;
  }
}

/// The trace's lines up to `end_s` of simulated time.
std::string traceUntil(const std::filesystem::path& trace, double end_s) {
  std::ifstream in(trace);
  std::string kept, line;
  while (std::getline(in, line) && (line.starts_with("t_s") || std::stod(line) <= end_s)) kept += line + "\n";
  return kept;
}

/// When the trial's stream began on the emulator's clock (its last "a stream began at" line).
double streamStart_s(const std::filesystem::path& emulator_err) {
  std::istringstream lines(fileText(emulator_err));
  double start = -1.0;
  const std::string marker = "a stream began at ";
  for (std::string line; std::getline(lines, line);) {
    if (const auto at = line.find(marker); at != std::string::npos) start = std::stod(line.substr(at + marker.size()));
  }
  return start;
}

TEST_F(OpenPenCli, TwoLockstepRunsGiveTheSameTraceBitForBit) {
  // Up to the trial's end on the pen's clock: after it, when hattr stops answering and hangs up is
  // the wall clock's choice (the recording does not see it).
  const std::string record = fmt::format("record --hand {}", script().string());
  const HapticProfile first = onTheFirmware(dir_, record, script(), dir_ / "first.csv", dir_ / "first-trace.csv");
  const double first_start_s = streamStart_s(dir_ / "emulator.err");
  const HapticProfile second = onTheFirmware(dir_, record, script(), dir_ / "second.csv", dir_ / "second-trace.csv");
  ASSERT_EQ(streamStart_s(dir_ / "emulator.err"), first_start_s);
  ASSERT_GT(first_start_s, 0.0);
  const double end_s = first_start_s + 0.3 + first.duration_s();  // the settle phase, then the recording
  const std::string trace = traceUntil(dir_ / "first-trace.csv", end_s);
  EXPECT_GT(trace.size(), 400'000u);
  EXPECT_TRUE(trace == traceUntil(dir_ / "second-trace.csv", end_s)) << "the plant's traces differ";
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) ASSERT_TRUE(first[i] == second[i]) << "sample " << i;
}

}  // namespace
}  // namespace hattr::test
