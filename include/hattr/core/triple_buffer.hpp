#pragma once
/// A lock-free triple buffer: one writer publishes the newest value every tick, one
/// reader (a GUI) takes the newest published value whenever it likes. Neither ever waits;
/// the reader may skip values, never sees a torn one.

#include <array>
#include <atomic>
#include <cstdint>

namespace hattr {

template <typename T>
class TripleBuffer {
 public:
  /// Writer only: publishes `value` as the newest.
  void write(const T& value) noexcept {
    buffers_[write_index_] = value;
    const std::uint8_t previous =
        middle_.exchange(static_cast<std::uint8_t>(write_index_ | kFresh), std::memory_order_acq_rel);
    write_index_ = previous & kIndexMask;
  }

  /// Reader only: copies the newest published value into `out`; false if nothing new was
  /// published since the last read (out still holds the last value read).
  bool read(T& out) noexcept {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) {
      out = buffers_[read_index_];
      return false;
    }
    const std::uint8_t previous = middle_.exchange(read_index_, std::memory_order_acq_rel);
    read_index_ = previous & kIndexMask;
    out = buffers_[read_index_];
    return true;
  }

 private:
  static constexpr std::uint8_t kFresh = 0x4;
  static constexpr std::uint8_t kIndexMask = 0x3;
  std::array<T, 3> buffers_{};
  std::uint8_t write_index_ = 0;
  std::uint8_t read_index_ = 1;
  std::atomic<std::uint8_t> middle_{2};
};

}  // namespace hattr
