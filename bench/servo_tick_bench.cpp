// Ticks per second of the full servo pipeline in simulated time: the simulated pen held by
// a hand writing circles, paper contact (512×512 grain relief, friction, texture), a
// guidance stage, the safety path, and the sample ring drained by a recorder-like consumer.
//   build/release/bench/bench_servo_tick

#include <benchmark/benchmark.h>

#include "hattr/device/simulated_device.hpp"
#include "hattr/render/paper_renderer.hpp"
#include "hattr/servo/servo_loop.hpp"

namespace {

using namespace hattr;

/// A PD pull toward a moving point: the arithmetic of position guidance.
class PullGuidance final : public GuidanceController {
 public:
  Vec3 compute(const PenState& pen, const ContactForces&, double) noexcept override {
    const Vec3 target(0.015 * std::cos(6.283 * pen.t_s), 0.015 * std::sin(6.283 * pen.t_s), 0.0);
    return 350.0 * (target - pen.p_WT) - 1.0 * pen.v_WT;
  }
};

void BM_ServoTickFullPipeline(benchmark::State& state) {
  device::CircleHand hand(Vec3::Zero(), 0.015, 1.0, 1.0);
  device::SimulatedDevice device(device::SimulatedPenParams{}, &hand);
  render::PaperRenderer paper(render::PaperParams{}, render::HeightField::paperGrain(0.16, 512, 1e-5, 5e-4, 2));
  PullGuidance guidance;
  servo::ServoLoop loop(device, servo::ServoConfig{});
  loop.setWorld(&paper);
  loop.setGuidance(&guidance);
  Sample drained;
  std::int64_t ticks = 0;
  for (auto _ : state) {
    loop.runSimulated(1000);
    while (loop.samples().tryPop(drained)) benchmark::DoNotOptimize(drained);
    ticks += 1000;
  }
  state.SetItemsProcessed(ticks);
  state.counters["time_per_tick"] = benchmark::Counter(static_cast<double>(ticks),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

BENCHMARK(BM_ServoTickFullPipeline)->Unit(benchmark::kMicrosecond);

}  // namespace
