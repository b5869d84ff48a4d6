#pragma once
/// A bounded, lock-free, single-producer / single-consumer ring. The producer (the servo
/// thread) never blocks and never allocates: when the ring is full, tryPush returns false
/// and the producer counts the drop. Capacity is fixed at construction (allocation there).

#include <atomic>
#include <cstddef>
#include <new>
#include <vector>

#include "hattr/core/error.hpp"

namespace hattr {

template <typename T>
class SpscRing {
 public:
  /// `capacity` slots (a power of two >= 2). Not on the servo thread.
  explicit SpscRing(std::size_t capacity) : slots_(capacity), mask_(capacity - 1) {
    HATTR_DEMAND(capacity >= 2 && (capacity & (capacity - 1)) == 0,
                 "capacity must be a power of two >= 2, got {}", capacity);
  }

  /// Producer only. False (and nothing written) when full.
  bool tryPush(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ == slots_.size()) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ == slots_.size()) return false;
    }
    slots_[head & mask_] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer only. False when empty.
  bool tryPop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    out = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Items waiting; exact for the consumer, a snapshot for anyone else.
  [[nodiscard]] std::size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }
  [[nodiscard]] std::size_t capacity() const noexcept { return slots_.size(); }

 private:
  static constexpr std::size_t kLine = 64;  // keep producer and consumer indices apart
  std::vector<T> slots_;
  std::size_t mask_;
  alignas(kLine) std::atomic<std::size_t> head_{0};
  std::size_t tail_cache_ = 0;  // producer's view of tail_
  alignas(kLine) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;  // consumer's view of head_
};

}  // namespace hattr
