#pragma once
// Private to the analysis module: the one way its functions share work among threads.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace hattr::analysis::detail {

/// Runs `chunk_costs(first, last)` over the items [0, count) in chunks of `chunk`, taken in turn
/// by `threads` threads (this one among them), at most as many as the hardware runs at once:
/// more would only time-slice the cores and evict each other's rows from their caches. The
/// first exception a chunk throws is rethrown here once every thread has stopped.
template <class ChunkCosts>
void forEachChunk(std::size_t count, std::size_t chunk, unsigned threads, const ChunkCosts& chunk_costs) {
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const auto work = [&] {
    try {
      for (std::size_t first = next.fetch_add(chunk); first < count; first = next.fetch_add(chunk)) {
        chunk_costs(first, std::min(count, first + chunk));
      }
    } catch (...) {
      const std::lock_guard lock(failure_mutex);
      if (!failure) failure = std::current_exception();
    }
  };
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> workers;
  for (unsigned t = 1; t < std::min(threads, hardware) && t * chunk < count; ++t) workers.emplace_back(work);
  work();
  for (auto& worker : workers) worker.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace hattr::analysis::detail
