// DTW speed in cells per second (one cell = one D(i, j)), single thread unless named:
//  - DtwPair: dtwDistance on one pair (SIMD over anti-diagonals);
//  - DtwBatch: dtwBatch on many equal-length pairs (SIMD lanes = pairs);
//  - DtwBatchSimilar: the same on pairs of a series and a warped, noisy copy of it, as a
//    trial is to its expert: the kernel prunes the cells off the best path (the cell rate
//    counts all n x n cells, so it is the rate a full computation would need to keep up);
//  - DtwReference: the plain full-matrix dtwReference, the baseline for the ratios;
//  - DtwScalarTwoRows: a tidy scalar two-row loop written here, a second, fairer baseline;
//  - DtwCostMatrix: all pairs of 24 series with 2 threads.
// Random-walk series of doubles, |x - y| cost, no band unless the name says band10.
//   build/release/bench/bench_dtw --benchmark_counters_tabular=true
//   build/release/bench/bench_dtw --benchmark_counters_tabular=true --dtw_max_avx2

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string_view>
#include <vector>

#include <benchmark/benchmark.h>
#include <hwy/targets.h>

#include "hattr/analysis/dtw.hpp"

namespace {

using namespace hattr::analysis;

std::vector<double> randomWalk(std::mt19937_64& rng, std::size_t n) {
  std::normal_distribution<double> step(0.0, 1.0);
  std::vector<double> s(n);
  double x = 0.0;
  for (auto& v : s) v = x += step(rng);
  return s;
}

void setCellRate(benchmark::State& state, double cells_per_iteration) {
  state.counters["cells_per_s"] =
      benchmark::Counter(cells_per_iteration, benchmark::Counter::kIsIterationInvariantRate);
}

// Two rows, no band, no checks: what a careful scalar implementation looks like.
double scalarTwoRows(const std::vector<double>& a, const std::vector<double>& b) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> prev(b.size() + 1, kInf);
  std::vector<double> cur(b.size() + 1, kInf);
  prev[0] = 0.0;
  for (const double x : a) {
    cur[0] = kInf;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      cur[j] = std::abs(x - b[j - 1]) + std::min(std::min(prev[j], prev[j - 1]), cur[j - 1]);
    }
    std::swap(prev, cur);
    prev[0] = kInf;
  }
  return prev[b.size()];
}

void DtwPair(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const double band = state.range(1) == 0 ? -1.0 : 0.01 * static_cast<double>(state.range(1));
  std::mt19937_64 rng(1);
  const auto a = randomWalk(rng, n);
  const auto b = randomWalk(rng, n);
  for (auto _ : state) benchmark::DoNotOptimize(dtwDistance(a, b, {.band_fraction = band}));
  const std::size_t r = dtwBandRadius(n, n, band);
  // Cells inside the band |i - j| <= r.
  double cells = static_cast<double>(n) * static_cast<double>(n);
  if (r != kNoBand) cells -= static_cast<double>(n - r - 1) * static_cast<double>(n - r);
  setCellRate(state, cells);
}
BENCHMARK(DtwPair)->ArgNames({"n", "band_pct"})->Args({1000, 0})->Args({4000, 0})->Args({4000, 10});

// dtwBatch on `pairs` pairs (state's arguments n, pairs): a random walk and partner(rng, it).
template <class Partner>
void batchOfPairs(benchmark::State& state, std::uint64_t seed, const Partner& partner) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const auto pairs = static_cast<std::size_t>(state.range(1));
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> as, bs;
  for (std::size_t p = 0; p < pairs; ++p) {
    as.push_back(randomWalk(rng, n));
    bs.push_back(partner(rng, as.back()));
  }
  for (auto _ : state) benchmark::DoNotOptimize(dtwBatch(as, bs));
  setCellRate(state, static_cast<double>(n * n * pairs));
}

void DtwBatch(benchmark::State& state) {
  batchOfPairs(state, 2, [](std::mt19937_64& rng, const std::vector<double>& a) { return randomWalk(rng, a.size()); });
}
BENCHMARK(DtwBatch)
    ->ArgNames({"n", "pairs"})
    ->Args({1000, 64})
    ->Args({4000, 32})
    ->Unit(benchmark::kMillisecond);

// A copy of `a` warped smoothly in time by up to 5 % of its length, plus noise.
std::vector<double> warpedCopy(std::mt19937_64& rng, const std::vector<double>& a) {
  std::normal_distribution<double> noise(0.0, 0.5);
  const double phase = std::uniform_real_distribution<double>(0.0, 6.28)(rng);
  const double last = static_cast<double>(a.size() - 1);
  std::vector<double> b(a.size());
  for (std::size_t j = 0; j < b.size(); ++j) {
    const double u = static_cast<double>(j) / last;
    const double t = std::clamp(u + 0.05 * std::sin(3.14159 * u) * std::sin(phase + 2.0 * u), 0.0, 1.0) * last;
    const auto i = std::min(static_cast<std::size_t>(t), a.size() - 2);
    b[j] = a[i] + (t - static_cast<double>(i)) * (a[i + 1] - a[i]) + noise(rng);
  }
  return b;
}

void DtwBatchSimilar(benchmark::State& state) { batchOfPairs(state, 3, warpedCopy); }
BENCHMARK(DtwBatchSimilar)->ArgNames({"n", "pairs"})->Args({4000, 32})->Unit(benchmark::kMillisecond);

void DtwReference(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::mt19937_64 rng(1);
  const auto a = randomWalk(rng, n);
  const auto b = randomWalk(rng, n);
  for (auto _ : state) benchmark::DoNotOptimize(dtwReference(a, b));
  setCellRate(state, static_cast<double>(n * n));
}
BENCHMARK(DtwReference)->ArgName("n")->Arg(1000)->Arg(4000)->Unit(benchmark::kMillisecond);

void DtwScalarTwoRows(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::mt19937_64 rng(1);
  const auto a = randomWalk(rng, n);
  const auto b = randomWalk(rng, n);
  for (auto _ : state) benchmark::DoNotOptimize(scalarTwoRows(a, b));
  setCellRate(state, static_cast<double>(n * n));
}
BENCHMARK(DtwScalarTwoRows)->ArgName("n")->Arg(1000)->Arg(4000)->Unit(benchmark::kMillisecond);

void DtwCostMatrix(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  constexpr std::size_t kSeries = 24;
  std::mt19937_64 rng(3);
  std::vector<std::vector<double>> series;
  for (std::size_t s = 0; s < kSeries; ++s) series.push_back(randomWalk(rng, n));
  for (auto _ : state) benchmark::DoNotOptimize(dtwCostMatrix(series, {}, 2));
  setCellRate(state, static_cast<double>(n * n * kSeries * (kSeries - 1) / 2));
}
BENCHMARK(DtwCostMatrix)->ArgName("n")->Arg(1000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

// --dtw_max_avx2: run the kernels as on a CPU without AVX-512 (same binary).
int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  const auto last = std::remove_if(argv + 1, argv + argc, [](const char* arg) {
    return std::string_view(arg) == "--dtw_max_avx2";
  });
  if (last != argv + argc) hwy::DisableTargets(HWY_AVX3 | HWY_AVX3_DL);
  argc = static_cast<int>(last - argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("dtw_simd_target", dtwSimdTarget());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
