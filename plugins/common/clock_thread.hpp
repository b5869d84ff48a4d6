#pragma once
// The clock of an in-tree plugin that owns its servo thread (sim and replay with clock=device):
// a thread calls the host's tick once per period on absolute deadlines, as vendor schedulers do,
// until stopped; `on_stop` runs on that thread after its last tick (e.g. zero the force).

#include <atomic>
#include <functional>
#include <thread>

#include "hattr/core/error.hpp"
#include "hattr/device/device.hpp"
#include "hattr/servo/realtime.hpp"

namespace hattr::plugins {

class ClockThread {
 public:
  explicit ClockThread(std::chrono::nanoseconds period) : period_(period) {}
  ~ClockThread() { stop(); }
  ClockThread(const ClockThread&) = delete;
  ClockThread& operator=(const ClockThread&) = delete;

  void start(device::DeviceTickFn tick, void* context, std::function<void()> on_stop = {}) {
    HATTR_DEMAND(!thread_.joinable(), "the plugin's clock is already running");
    stop_.store(false);
    thread_ = std::thread([this, tick, context, on_stop = std::move(on_stop)] {
      const auto start = servo::monotonicNow();
      auto deadline = start;
      while (!stop_.load(std::memory_order_acquire)) {
        tick(context, servo::monotonicNow() - start);
        deadline += period_;
        servo::sleepUntil(deadline, std::chrono::nanoseconds(0));
      }
      if (on_stop) on_stop();
    });
  }
  void stop() noexcept {
    stop_.store(true, std::memory_order_release);
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::chrono::nanoseconds period_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace hattr::plugins
