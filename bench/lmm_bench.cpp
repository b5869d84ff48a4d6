// Linear mixed-model fits of 10 000 observations (issue 37's target: < 100 ms each), from
// a seeded simulated study so every run fits the same data:
//  - LmmSlopes: cost ~ mode * trial + (1 + trial | subject), 100 subjects × 3 modes ×
//    34 trials minus 200 missing (two correlated random effects a subject);
//  - LmmCrossed: score ~ group + (1 | subject) + (1 | item), 200 subjects × 50 items
//    (two crossed random effects);
// each with Satterthwaite's degrees of freedom and the type III tests (the whole fit) and
// without them (/no_tests: the REML optimization alone).
//   build/release/bench/bench_lmm

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include "hattr/analysis/lmm.hpp"

namespace {

using namespace hattr::analysis;

DataTable slopesData() {
  std::mt19937_64 rng(37);
  std::normal_distribution<double> noise(0.0, 1.5);
  std::normal_distribution<double> intercept(0.0, 2.0);
  std::normal_distribution<double> slope(0.0, 0.3);
  DataTable t{{{"subject", {}, {}}, {"mode", {}, {}}, {"trial", {}, {}}, {"cost", {}, {}}}, "simulated"};
  const char* modes[] = {"ALPHA", "BASIC", "PCONTROL"};
  std::vector<std::size_t> skip;
  std::uniform_int_distribution<std::size_t> row(0, 100 * 3 * 34 - 1);
  for (int i = 0; i < 200; ++i) skip.push_back(row(rng));
  std::size_t index = 0;
  for (int s = 0; s < 100; ++s) {
    const double u0 = intercept(rng);
    const double u1 = slope(rng);
    for (int m = 0; m < 3; ++m) {
      for (int trial = 1; trial <= 34; ++trial, ++index) {
        if (std::find(skip.begin(), skip.end(), index) != skip.end()) continue;
        t.columns[0].text.push_back(fmt::format("s{:03}", s));
        t.columns[1].text.push_back(modes[m]);
        t.columns[2].numbers.push_back(trial);
        t.columns[3].numbers.push_back(20.0 - m + u0 + (u1 - 0.1) * trial + noise(rng));
      }
    }
  }
  return t;
}

DataTable crossedData() {
  std::mt19937_64 rng(38);
  std::normal_distribution<double> noise(0.0, 0.6);
  std::normal_distribution<double> subject_effect(0.0, 0.7);
  std::normal_distribution<double> item_effect(0.0, 0.5);
  DataTable t{{{"subject", {}, {}}, {"item", {}, {}}, {"group", {}, {}}, {"score", {}, {}}}, "simulated"};
  std::vector<double> items(50);
  for (double& v : items) v = item_effect(rng);
  const char* groups[] = {"fading", "free", "guided"};
  for (int s = 0; s < 200; ++s) {
    const double u = subject_effect(rng);
    for (int i = 0; i < 50; ++i) {
      t.columns[0].text.push_back(fmt::format("p{:03}", s));
      t.columns[1].text.push_back(fmt::format("c{:02}", i));
      t.columns[2].text.push_back(groups[s % 3]);
      t.columns[3].numbers.push_back(5.0 - 0.3 * (s % 3) + u + items[static_cast<std::size_t>(i)] + noise(rng));
    }
  }
  return t;
}

void fit(benchmark::State& state, const DataTable& data, const char* formula, bool tests) {
  std::size_t evaluations = 0;
  for (auto _ : state) {
    const LmmFit f = fitLmm(data, formula, {.tests = tests});
    evaluations = f.evaluations;
    benchmark::DoNotOptimize(f.criterion);
  }
  state.counters["observations"] = static_cast<double>(data.columns[3].numbers.size());
  state.counters["deviance_evaluations"] = static_cast<double>(evaluations);
}

void LmmSlopes(benchmark::State& state) {
  static const DataTable data = slopesData();
  fit(state, data, "cost ~ mode * trial + (1 + trial | subject)", state.range(0) != 0);
}
void LmmCrossed(benchmark::State& state) {
  static const DataTable data = crossedData();
  fit(state, data, "score ~ group + (1 | subject) + (1 | item)", state.range(0) != 0);
}

BENCHMARK(LmmSlopes)->Arg(1)->Arg(0)->ArgName("tests")->Unit(benchmark::kMillisecond);
BENCHMARK(LmmCrossed)->Arg(1)->Arg(0)->ArgName("tests")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
