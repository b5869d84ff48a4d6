#include "hattr/core/histogram.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace hattr {

// Values below kSubBuckets get one bucket each; above, each power of two is split into
// kSubBuckets equal buckets.
int DurationHistogram::bucketOf(std::uint64_t ns) noexcept {
  if (ns < kSubBuckets) return static_cast<int>(ns);
  const int msb = static_cast<int>(std::bit_width(ns)) - 1;  // >= 5
  const int shift = msb - 5;                            // log2(kSubBuckets) = 5
  const int sub = static_cast<int>((ns >> shift) & (kSubBuckets - 1));
  const int bucket = (shift + 1) * kSubBuckets + sub;
  return std::min(bucket, kSubBuckets * kMajors - 1);
}

std::uint64_t DurationHistogram::upperEdgeOf(int bucket) noexcept {
  if (bucket < kSubBuckets) return static_cast<std::uint64_t>(bucket);
  const int shift = bucket / kSubBuckets - 1;
  const std::uint64_t sub = static_cast<std::uint64_t>(bucket % kSubBuckets) + kSubBuckets;
  return ((sub + 1) << shift) - 1;
}

void DurationHistogram::record(std::int64_t ns) noexcept {
  const std::uint64_t value = ns > 0 ? static_cast<std::uint64_t>(ns) : 0;
  ++buckets_[static_cast<std::size_t>(bucketOf(value))];
  ++count_;
  max_ns_ = std::max(max_ns_, static_cast<std::int64_t>(value));
}

void DurationHistogram::clear() noexcept {
  buckets_.fill(0);
  count_ = 0;
  max_ns_ = 0;
}

std::int64_t DurationHistogram::percentile_ns(double fraction) const noexcept {
  if (count_ == 0) return 0;
  const double clamped = std::clamp(fraction, 0.0, 1.0);
  const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(clamped * static_cast<double>(count_))));
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < buckets_.size(); ++b) {
    seen += buckets_[b];
    if (seen >= rank) {
      return std::min(static_cast<std::int64_t>(upperEdgeOf(static_cast<int>(b))), max_ns_);
    }
  }
  return max_ns_;
}

}  // namespace hattr
