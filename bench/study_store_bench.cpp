// Storing and reading a finished trial in the study database, as the runner and the analysis
// do: the simulated expert writing 'Na' (about 4.5 s at 1 kHz with tilt, like the demo's
// trials), committed in its own transaction with WAL and synchronous=FULL, compressed losslessly
// (docs/study-store.md); read back whole by trialProfile. The same on a PostgreSQL server when
// HATTR_BENCH_PG_STORE and HATTR_BENCH_PG_READ name two empty databases (bench/study_stations.sh
// starts a server and gives them).
//   build/release/bench/bench_study_store [--quick]
// --quick: 2 × 20 iterations: the smoke size bench/study_stations.sh --quick runs (the
// doc test), which proves the benchmark works and measures nothing.

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <benchmark/benchmark.h>

#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"

namespace {

using namespace hattr;

/// This process's scratch folder (two benchmark runs at once, as the doc tests may run them, must
/// not share one), removed when the program ends.
const std::filesystem::path& scratchRoot() {
  static const std::filesystem::path root =
      std::filesystem::temp_directory_path() / ("hattr-bench-study-" + std::to_string(::getpid()));
  return root;
}

/// The simulated expert's recording, made once.
const HapticProfile& trial() {
  static const HapticProfile recorded = [] {
    session::TrialEnvironment env("sim://pen", render::WorldConfig{}, 1000.0);
    const HapticProfile script = sim::expertScript(sim::loadGlyph(sim::defaultDataDir() / "glyphs" / "na.json"));
    return sim::recordExpert(env, script, {.subject = "S01", .skill = "na"});
  }();
  return recorded;
}

/// A study of one subject with 1000 planned trials, in a fresh folder (its file there, or in
/// the empty PostgreSQL database `postgres`), opened as its runner holding the subject.
session::StudyDatabase freshStudy(const std::filesystem::path& dir, const std::string& postgres = "") {
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
  session::applyPaperForm(study);
  const std::filesystem::path where = postgres.empty() ? dir / "s.sqlite" : std::filesystem::path(postgres);
  { (void)session::StudyDatabase::create(where, study); }
  session::StudyDatabase db = session::StudyDatabase::open(where, session::OpenMode::kRunner);
  if (!db.claimSubject("S01").granted) throw std::runtime_error("the benchmark's subject is held elsewhere");
  return db;
}

/// A benchmark database named by the environment ("" when not set).
std::string postgresFor(const char* variable) {
  const char* value = std::getenv(variable);
  return value ? value : "";
}

/// SQLite: a fresh study file for each run. PostgreSQL: the database the environment names,
/// made into the study at the first run and kept for the others (a database holds one study).
std::map<std::string, session::StudyDatabase>& keptStudies() {
  static std::map<std::string, session::StudyDatabase> kept;
  return kept;
}

session::StudyDatabase& studyFor(const std::filesystem::path& dir, const char* postgres_variable) {
  auto& kept = keptStudies();
  const std::string address = postgres_variable ? postgresFor(postgres_variable) : "";
  if (address.empty()) kept.erase(address);
  if (!kept.contains(address)) kept.emplace(address, freshStudy(dir, address));
  return kept.at(address);
}

/// The study's trials not completed yet.
std::vector<std::int64_t> pendingTrials(const session::StudyDatabase& db) {
  std::vector<std::int64_t> ids;
  for (const auto& t : db.trials()) {
    if (t.status != session::TrialStatus::kCompleted) ids.push_back(t.id);
  }
  return ids;
}

void BM_StoreTrial(benchmark::State& state, const char* postgres_variable) {
  session::StudyDatabase& db = studyFor(scratchRoot() / "store", postgres_variable);
  const auto pending = pendingTrials(db);
  std::size_t next = 0;
  for (auto _ : state) {
    if (next == pending.size()) {
      state.SkipWithError("no pending trial left to store");
      break;
    }
    db.completeTrial(pending[next++], trial(), "bench");
  }
  state.counters["samples"] = static_cast<double>(trial().size());
}

void BM_ReadTrial(benchmark::State& state, const char* postgres_variable) {
  session::StudyDatabase& db =
      studyFor(scratchRoot() / "read", postgres_variable);
  const auto trials = db.trials();
  const auto id = trials.front().id;
  if (trials.front().status != session::TrialStatus::kCompleted) db.completeTrial(id, trial(), "bench");
  for (auto _ : state) benchmark::DoNotOptimize(db.trialProfile(id));
  state.counters["samples"] = static_cast<double>(trial().size());
}

/// The SQLite benchmarks, and the PostgreSQL ones when their databases are given; 3 × 200
/// iterations each, or 2 × 20 when quick (two, for the means the scripts read).
void registerBenchmarks(bool quick) {
  const auto add = [quick](const char* name, void (*f)(benchmark::State&, const char*), const char* variable) {
    benchmark::RegisterBenchmark(name, f, variable)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(quick ? 20 : 200)
        ->Repetitions(quick ? 2 : 3)
        ->ReportAggregatesOnly(true);
  };
  add("BM_StoreTrial", BM_StoreTrial, nullptr);
  add("BM_ReadTrial", BM_ReadTrial, nullptr);
  if (!postgresFor("HATTR_BENCH_PG_STORE").empty()) add("BM_StoreTrialPostgres", BM_StoreTrial, "HATTR_BENCH_PG_STORE");
  if (!postgresFor("HATTR_BENCH_PG_READ").empty()) add("BM_ReadTrialPostgres", BM_ReadTrial, "HATTR_BENCH_PG_READ");
}

/// Takes --quick out of the arguments; whether it was there.
bool takeQuick(int& argc, char** argv) {
  const auto end = std::remove(argv + 1, argv + argc, std::string_view("--quick"));
  const bool quick = end != argv + argc;
  argc = static_cast<int>(end - argv);
  return quick;
}

}  // namespace

int main(int argc, char** argv) {
  registerBenchmarks(takeQuick(argc, argv));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  keptStudies().clear();  // closed before their folder goes
  std::error_code ignored;
  std::filesystem::remove_all(scratchRoot(), ignored);
  return 0;
}
