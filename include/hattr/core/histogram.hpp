#pragma once
/// A fixed log-linear histogram of non-negative durations in nanoseconds (1 ns to ~18 min,
/// 1/32 relative resolution: percentiles within about 3 %). Recording is O(1), noexcept and
/// never allocates, so the servo loop can measure itself.

#include <array>
#include <cstdint>

namespace hattr {

class DurationHistogram {
 public:
  static constexpr int kSubBuckets = 32;
  static constexpr int kMajors = 41;

  /// Records one value [ns]; negative values count as 0. Servo-thread safe.
  void record(std::int64_t ns) noexcept;
  void clear() noexcept;

  [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
  [[nodiscard]] std::int64_t max_ns() const noexcept { return max_ns_; }
  /// The value below which `fraction` (0..1) of the records fall [ns]: the upper edge of
  /// the bucket holding that rank, capped at the recorded maximum. 0 when empty.
  [[nodiscard]] std::int64_t percentile_ns(double fraction) const noexcept;

 private:
  static int bucketOf(std::uint64_t ns) noexcept;
  static std::uint64_t upperEdgeOf(int bucket) noexcept;
  std::array<std::uint64_t, kSubBuckets * kMajors> buckets_{};
  std::uint64_t count_ = 0;
  std::int64_t max_ns_ = 0;
};

}  // namespace hattr
