// Throughput of the haptic-profile CSV writer and reader: a 4 s trial at 1 kHz.
//   build/release/bench/bench_profile_io

#include <random>
#include <sstream>

#include <benchmark/benchmark.h>

#include "hattr/io/profile_csv.hpp"

namespace {

hattr::HapticProfile makeTrial(std::size_t samples) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 1.0);
  hattr::HapticProfile profile({.subject = "S1", .skill = "na", .nominal_rate_hz = 1000.0});
  for (std::size_t i = 0; i < samples; ++i) {
    hattr::Sample s;
    s.t_s = static_cast<double>(i) * 1e-3;
    s.p_WT = hattr::Vec3(0.01 * std::sin(s.t_s), 0.01 * std::cos(s.t_s), 1e-5 * noise(rng));
    s.v_WT = hattr::Vec3(noise(rng), noise(rng), noise(rng)) * 0.05;
    s.f_user_W = hattr::Vec3(noise(rng), noise(rng), -2.0 + noise(rng));
    s.f_cmd_W = -s.f_user_W;
    s.pen_down = s.in_contact = true;
    profile.append(s);
  }
  return profile;
}

void BM_WriteProfileCsv(benchmark::State& state) {
  const auto profile = makeTrial(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    std::ostringstream out;
    hattr::io::writeProfileCsv(profile, out);
    benchmark::DoNotOptimize(out.view().size());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_ReadProfileCsv(benchmark::State& state) {
  std::ostringstream out;
  hattr::io::writeProfileCsv(makeTrial(static_cast<std::size_t>(state.range(0))), out);
  const std::string text = out.str();
  for (auto _ : state) {
    std::istringstream in(text);
    benchmark::DoNotOptimize(hattr::io::readProfileCsv(in, "bench.csv").size());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(text.size()));
}

BENCHMARK(BM_WriteProfileCsv)->Arg(4000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadProfileCsv)->Arg(4000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
