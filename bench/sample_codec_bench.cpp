// The study store's sample encoding (io/sample_codec) on trials like the demo's: the expert
// writing 'Na' on the simulated pen (BASIC, no guidance) and a trainee's PCONTROL trial of the
// same script written 2 mm off (guidance forces on), each about 4.5 s at 1 kHz with tilt. Encode and decode
// times per trial, and the size ratio (raw doubles / encoded bytes) as a counter, lossless
// and at the default declared resolution.
//   build/release/bench/bench_sample_codec
// With --db STUDY.sqlite instead, it encodes every stored trial of a study both ways and prints
// the sizes as JSON (no timing):
//   build/release/bench/bench_sample_codec --db study.sqlite

#include <cstring>
#include <iostream>

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include "hattr/io/sample_codec.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"

namespace {

using namespace hattr;

struct Trials {
  HapticProfile expert;
  HapticProfile guided;
};

/// The two trials, simulated once.
const Trials& trials() {
  static const Trials t = [] {
    session::TrialEnvironment env("sim://pen", render::WorldConfig{}, 1000.0);
    const HapticProfile script = sim::expertScript(sim::loadGlyph(sim::defaultDataDir() / "glyphs" / "na.json"));
    Trials made;
    made.expert = sim::recordExpert(env, script, {.subject = "expert", .skill = "na"});
    // The trainee's hand writes the script 2 mm to the right of the expert: PCONTROL pulls it
    // back (0.35 N/mm: about 0.7 N of guidance), as in the demo's guided trials.
    HapticProfile shifted(script.metadata(), script.rawChannels());
    for (Sample s : script.samples()) {
      s.p_WT.x() += 0.002;
      shifted.append(s);
    }
    device::ProfileHandScript hand(shifted);
    session::TrialSetup setup;
    setup.duration_s = hand.duration_s();
    setup.reference = std::make_shared<guidance::ReferenceTrajectory>(made.expert, 1000.0);
    setup.guidance.mode = guidance::TrainingMode::kPositionControl;
    made.guided = session::runTrial(env, setup, hand).profile;
    return made;
  }();
  return t;
}

const HapticProfile& profileOf(benchmark::State& state) { return state.range(0) == 0 ? trials().expert : trials().guided; }

std::vector<Channel> storedChannels(const HapticProfile& p) {
  std::vector<Channel> channels;
  for (const auto& info : allChannels()) {
    if (!info.derived && !needsRawChannel(info.channel, p.rawChannels())) channels.push_back(info.channel);
  }
  return channels;
}

const io::ChannelResolution& resolutionOf(benchmark::State& state) {
  static const io::ChannelResolution lossless;
  return state.range(1) == 0 ? lossless : io::defaultResolution();
}

void setCounters(benchmark::State& state, const HapticProfile& p, std::size_t channels, std::size_t bytes) {
  state.counters["samples"] = static_cast<double>(p.size());
  state.counters["ratio"] = static_cast<double>(p.size() * channels * 8) / static_cast<double>(bytes);
}

void EncodeTrial(benchmark::State& state) {
  const HapticProfile& p = profileOf(state);
  const auto channels = storedChannels(p);
  std::string blob;
  for (auto _ : state) {
    blob = io::encodeSamples(p.samples(), channels, resolutionOf(state));
    benchmark::DoNotOptimize(blob.data());
  }
  setCounters(state, p, channels.size(), blob.size());
}

void DecodeTrial(benchmark::State& state) {
  const HapticProfile& p = profileOf(state);
  const auto channels = storedChannels(p);
  const std::string blob = io::encodeSamples(p.samples(), channels, resolutionOf(state));
  for (auto _ : state) benchmark::DoNotOptimize(io::decodeSamples(blob, channels, p.size()));
  setCounters(state, p, channels.size(), blob.size());
}

// Args: trial (0 the expert, 1 PCONTROL), resolution (0 lossless, 1 the default).
BENCHMARK(EncodeTrial)->ArgNames({"guided", "quantized"})->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(DecodeTrial)->ArgNames({"guided", "quantized"})->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);

/// Every stored trial of a study, encoded lossless and at the default resolution: the sizes.
int measureStudy(const char* file) {
  const auto db = session::StudyDatabase::open(file, session::OpenMode::kReadOnly);
  std::size_t trials = 0, samples = 0, raw = 0, lossless = 0, stepped = 0;
  for (const auto& t : db.trials()) {
    if (t.sample_count <= 0) continue;
    const HapticProfile p = db.trialProfile(t.id);
    const auto channels = storedChannels(p);
    ++trials;
    samples += p.size();
    raw += p.size() * channels.size() * 8;
    lossless += io::encodeSamples(p.samples(), channels).size();
    stepped += io::encodeSamples(p.samples(), channels, io::defaultResolution()).size();
  }
  std::cout << nlohmann::json{{"db", file},
                              {"trials", trials},
                              {"samples", samples},
                              {"raw_bytes", raw},
                              {"lossless_bytes", lossless},
                              {"default_resolution_bytes", stepped},
                              {"lossless_ratio", static_cast<double>(raw) / static_cast<double>(lossless)},
                              {"default_resolution_ratio", static_cast<double>(raw) / static_cast<double>(stepped)}}
                   .dump()
            << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "--db") == 0) return measureStudy(argv[2]);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
