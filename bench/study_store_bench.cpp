// Storing and reading a finished trial in the study database, as the runner and the analysis
// do: the simulated expert writing 'Na' (about 4.5 s at 1 kHz with tilt, like the demo's
// trials), committed in its own transaction with WAL and synchronous=FULL, compressed losslessly
// (docs/study-store.md); read back whole by trialProfile.
//   build/release/bench/bench_study_store

#include <filesystem>

#include <benchmark/benchmark.h>

#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"

namespace {

using namespace hattr;

/// The simulated expert's recording, made once.
const HapticProfile& trial() {
  static const HapticProfile recorded = [] {
    session::TrialEnvironment env("sim://pen", render::WorldConfig{}, 1000.0);
    const HapticProfile script = sim::expertScript(sim::loadGlyph(sim::defaultDataDir() / "glyphs" / "na.json"));
    return sim::recordExpert(env, script, {.subject = "S01", .skill = "na"});
  }();
  return recorded;
}

/// A study of one subject with 1000 planned trials, in a fresh folder.
session::StudyDatabase freshStudy(const std::filesystem::path& dir) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  io::writeProfileCsv(trial(), dir / "expert.csv");
  session::StudyDefinition study;
  study.name = "bench";
  study.skill = "na";
  study.experts["na"] = dir / "expert.csv";
  study.modes = {guidance::TrainingMode::kBasic};
  study.protocol.training_trials = 1000;
  study.protocol.recall_trials = 2;  // the smallest protocol the study file allows (recall 1 is a warm-up)
  study.subjects = {{"S01", "script", 1, nlohmann::json::object()}};
  { (void)session::StudyDatabase::create(dir / "s.sqlite", study); }
  return session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
}

void BM_StoreTrial(benchmark::State& state) {
  const auto dir = std::filesystem::temp_directory_path() / "hattr-bench-study";
  session::StudyDatabase db = freshStudy(dir);
  const auto trials = db.trials();
  std::size_t next = 0;
  for (auto _ : state) {
    db.completeTrial(trials[next % trials.size()].id, trial(), "bench");
    ++next;
  }
  state.counters["samples"] = static_cast<double>(trial().size());
  std::filesystem::remove_all(dir);
}

void BM_ReadTrial(benchmark::State& state) {
  const auto dir = std::filesystem::temp_directory_path() / "hattr-bench-study-read";
  session::StudyDatabase db = freshStudy(dir);
  const auto id = db.trials().front().id;
  db.completeTrial(id, trial(), "bench");
  for (auto _ : state) benchmark::DoNotOptimize(db.trialProfile(id));
  state.counters["samples"] = static_cast<double>(trial().size());
  std::filesystem::remove_all(dir);
}

BENCHMARK(BM_StoreTrial)->Unit(benchmark::kMillisecond)->Iterations(200)->Repetitions(3)->ReportAggregatesOnly(true);
BENCHMARK(BM_ReadTrial)->Unit(benchmark::kMillisecond)->Iterations(200)->Repetitions(3)->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
