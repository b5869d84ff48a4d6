// Storing a finished trial in the study database: a 4 s trial at 1 kHz (4 000 samples with
// tilt), committed in its own transaction with WAL and synchronous=FULL, as the runner does.
//   build/release/bench/bench_study_store

#include <cmath>
#include <filesystem>

#include <benchmark/benchmark.h>

#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"

namespace {

using namespace hattr;

HapticProfile trial(std::size_t samples) {
  HapticProfile p({.subject = "S01", .skill = "na", .nominal_rate_hz = 1000.0}, RawChannels{.tilt = true});
  for (std::size_t i = 0; i < samples; ++i) {
    Sample s;
    s.t_s = static_cast<double>(i) * 1e-3;
    s.p_WT = Vec3(0.01 * std::sin(s.t_s), 0.01 * std::cos(s.t_s), -0.002);
    s.f_user_W = Vec3(0.1, 0.2, -1.2 - 0.1 * std::sin(s.t_s));
    s.pen_down = s.in_contact = true;
    s.tilt_altitude_rad = 1.0;
    p.append(s);
  }
  return p;
}

void BM_StoreTrial4sAt1kHz(benchmark::State& state) {
  const auto dir = std::filesystem::temp_directory_path() / "hattr-bench-study";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const HapticProfile profile = trial(4000);
  io::writeProfileCsv(profile, dir / "expert.csv");
  session::StudyDefinition study;
  study.name = "bench";
  study.skill = "na";
  study.experts["na"] = dir / "expert.csv";
  study.modes = {guidance::TrainingMode::kBasic};
  study.protocol.training_trials = 1000;
  study.protocol.recall_trials = 2;  // the smallest protocol the study file allows (recall 1 is a warm-up)
  study.subjects = {{"S01", "script", 1, nlohmann::json::object()}};
  { (void)session::StudyDatabase::create(dir / "s.sqlite", study); }
  session::StudyDatabase db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
  const auto trials = db.trials();
  std::size_t next = 0;
  for (auto _ : state) {
    db.completeTrial(trials[next % trials.size()].id, profile, "bench");
    ++next;
  }
  std::filesystem::remove_all(dir);
}

BENCHMARK(BM_StoreTrial4sAt1kHz)->Unit(benchmark::kMillisecond)->Iterations(200)->Repetitions(3)->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
