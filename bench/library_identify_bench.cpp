// Identification in a large profile library (issue 61): the exact search (LB_Keogh, then
// early-abandoned DTW: library::identify) against exhaustive DTW (every distance, by the batch
// kernel, the fastest exhaustive way), on the same queries and threads, with their top-K compared.
//
//   bench_library_identify [--writers 10000] [--takes 10] [--queries 1000] [--top 5]
//                          [--features shape+force] [--threads 2] [--json]
//
// Simulated writers (tests/library/synthetic_writers.hpp): each a curve, a pressure rhythm and a
// tilt of their own, each take varied from a seed. Memory: the features the search keeps, per
// profile length × channels × 8 bytes, reported with the process's peak.

#include <sys/resource.h>

#include <algorithm>
#include <cstdlib>
#include <atomic>
#include <chrono>
#include <iostream>
#include <map>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "hattr/analysis/dtw.hpp"
#include "hattr/library/matching.hpp"
#include "library/synthetic_writers.hpp"

using namespace hattr;

namespace {

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// Runs f(i) for i in [0, n) on `threads` threads.
template <class F>
void parallelFor(std::size_t n, unsigned threads, F f) {
  std::atomic<std::size_t> next{0};
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t) {
    pool.emplace_back([&] {
      for (std::size_t i = next++; i < n; i = next++) f(i);
    });
  }
  for (auto& t : pool) t.join();
}

/// Only the set's channels, so memory is what a search over it needs.
library::FeatureSeries keepOnly(library::FeatureSeries f, library::FeatureSet set) {
  library::FeatureSeries out;
  out.writing_time_s = f.writing_time_s;
  for (const auto c : set.channels()) {
    out.channels[static_cast<std::size_t>(c)] = std::move(f.channels[static_cast<std::size_t>(c)]);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  int writers = 10000, takes = 10, queries = 1000;
  std::size_t top = 5;
  unsigned threads = 2;
  std::string features = "shape+force";
  bool json = false;
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    const char* value = i + 1 < argc ? argv[i + 1] : "";
    if (a == "--json") {
      json = true;
      continue;
    }
    ++i;
    if (a == "--writers") writers = std::atoi(value);
    else if (a == "--takes") takes = std::atoi(value);
    else if (a == "--queries") queries = std::atoi(value);
    else if (a == "--top") top = static_cast<std::size_t>(std::atol(value));
    else if (a == "--threads") threads = static_cast<unsigned>(std::atol(value));
    else if (a == "--features") features = value;
    else {
      std::cerr << "bench_library_identify: unknown argument " << a << '\n';
      return 2;
    }
  }
  if (writers < 1 || takes < 1 || queries < 1 || top < 1 || threads < 1) {
    std::cerr << "bench_library_identify: --writers, --takes, --queries, --top and --threads must be at least 1\n";
    return 2;
  }
  const library::FeatureSet set = library::parseFeatureSet(features);
  const library::FeatureOptions options;

  // The library: writers × takes profiles' features.
  auto started = std::chrono::steady_clock::now();
  std::vector<library::Candidate> candidates(static_cast<std::size_t>(writers) * static_cast<std::size_t>(takes));
  parallelFor(candidates.size(), threads, [&](std::size_t i) {
    const int w = static_cast<int>(i) / takes, t = static_cast<int>(i) % takes;
    candidates[i] = {fmt::format("W{}", w), fmt::format("W{}/{}", w, t),
                     keepOnly(library::extractFeatures(test::syntheticSignature(w, t), options, "library"), set)};
  });
  const double build_s = seconds(started);
  std::vector<library::FeatureSeries> probes(static_cast<std::size_t>(queries));
  parallelFor(probes.size(), threads, [&](std::size_t q) {
    const int w = static_cast<int>((q * 7919u) % static_cast<std::size_t>(writers));
    probes[q] = keepOnly(library::extractFeatures(test::syntheticSignature(w, takes + static_cast<int>(q), 99), options, "q"), set);
  });

  // The index (the candidates' series side by side), then the exact search, a query a thread at a time.
  started = std::chrono::steady_clock::now();
  const library::SearchIndex index(candidates, set, options);
  const double index_s = seconds(started);
  std::vector<library::SearchStats> stats;
  started = std::chrono::steady_clock::now();
  const auto fast = library::identifyMany(probes, index, top, threads, &stats);
  const double fast_s = seconds(started);

  // Exhaustive: every distance by the batch kernel (all threads), then ranked per person.
  std::vector<std::vector<library::RankedPerson>> brute(probes.size());
  analysis::DtwOptions dtw;
  dtw.band_fraction = options.band_fraction;
  const auto channels = set.channels();
  started = std::chrono::steady_clock::now();
  for (std::size_t q = 0; q < probes.size(); ++q) {
    std::vector<double> sum(candidates.size(), 0.0);
    for (std::size_t k = 0; k < channels.size(); ++k) {
      std::vector<std::span<const double>> a(candidates.size(), std::span<const double>(probes[q][channels[k]]));
      std::vector<std::span<const double>> b;
      b.reserve(candidates.size());
      for (std::size_t i = 0; i < index.size(); ++i) b.emplace_back(index.series(i, k));
      const auto d = analysis::dtwBatch(std::span<const std::span<const double>>(a), std::span<const std::span<const double>>(b), dtw, threads);
      for (std::size_t i = 0; i < d.size(); ++i) sum[i] += d[i];
    }
    std::map<std::string, library::RankedPerson> best;
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const double d = sum[i] / static_cast<double>(options.length) + library::timingDistance(probes[q], candidates[i].features, set, options);
      auto [it, fresh] = best.try_emplace(candidates[i].person, library::RankedPerson{candidates[i].person, candidates[i].key, d});
      if (!fresh && (d < it->second.distance || (d == it->second.distance && candidates[i].key < it->second.key))) {
        it->second = {candidates[i].person, candidates[i].key, d};
      }
    }
    std::vector<library::RankedPerson> ranked;
    for (auto& [p, r] : best) ranked.push_back(r);
    std::sort(ranked.begin(), ranked.end(), [](const auto& x, const auto& y) {
      return x.distance != y.distance ? x.distance < y.distance : x.person < y.person;
    });
    ranked.resize(std::min(top, ranked.size()));
    brute[q] = std::move(ranked);
  }
  const double brute_s = seconds(started);

  // Same persons in the same order; distances equal to rounding (the batch and single kernels
  // sum the same cells in other orders).
  std::size_t same = 0;
  for (std::size_t q = 0; q < probes.size(); ++q) {
    bool ok = fast[q].size() == brute[q].size();
    for (std::size_t k = 0; ok && k < fast[q].size(); ++k) {
      ok = fast[q][k].person == brute[q][k].person &&
           std::abs(fast[q][k].distance - brute[q][k].distance) <= 1e-9 * std::max(1.0, brute[q][k].distance);
    }
    same += ok ? 1 : 0;
  }
  std::size_t full = 0, abandoned = 0, keogh = 0, pruned = 0;
  for (const auto& s : stats) full += s.dtw_full, abandoned += s.dtw_abandoned, keogh += s.lower_bounds, pruned += s.pruned_by_keogh;
  const std::size_t feature_bytes = index.bytes();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);

  const nlohmann::json out{{"profiles", candidates.size()}, {"writers", writers}, {"queries", queries}, {"top", top},
                           {"features", set.name()}, {"length", options.length}, {"band", options.band_fraction},
                           {"threads", threads}, {"build_s", build_s}, {"index_s", index_s}, {"exact_search_s", fast_s},
                           {"exhaustive_s", brute_s}, {"speedup", brute_s / fast_s},
                           {"identical_top_k", same}, {"full_dtw_per_query", static_cast<double>(full) / queries},
                           {"abandoned_dtw_per_query", static_cast<double>(abandoned) / queries},
                           {"lb_keogh_per_query", static_cast<double>(keogh) / queries},
                           {"pruned_by_lb_keogh_per_query", static_cast<double>(pruned) / queries},
                           {"index_megabytes", static_cast<double>(feature_bytes) / 1e6},
                           {"peak_rss_megabytes", static_cast<double>(usage.ru_maxrss) / 1e3},
                           {"simd", analysis::dtwSimdTarget()}};
  if (json) {
    std::cout << out.dump(2) << '\n';
  } else {
    std::cout << fmt::format("{} profiles, {} queries, top {}: exact search {:.1f} s, exhaustive {:.1f} s ({:.1f}x); "
                             "identical top-K on {} of {}; {:.0f} full DTWs a query; index {:.0f} MB, peak {:.0f} MB\n",
                             candidates.size(), queries, top, fast_s, brute_s, brute_s / fast_s, same, queries,
                             static_cast<double>(full) / queries, static_cast<double>(feature_bytes) / 1e6,
                             static_cast<double>(usage.ru_maxrss) / 1e3);
  }
  return same == probes.size() ? 0 : 1;
}
