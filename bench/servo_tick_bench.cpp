// Ticks per second of the full servo pipeline in simulated time: the simulated pen held by
// a hand writing circles, paper contact (512×512 grain relief, friction, texture), ALPHA
// force guidance against an expert reference, the safety path, and the recorder taking
// every sample into a haptic profile.
//   build/release/bench/bench_servo_tick

#include <cmath>

#include <benchmark/benchmark.h>

#include "hattr/device/simulated_device.hpp"
#include "hattr/guidance/training_guidance.hpp"
#include "hattr/render/paper_renderer.hpp"
#include "hattr/servo/servo_loop.hpp"
#include "hattr/session/recorder.hpp"

namespace {

using namespace hattr;

/// An expert reference: the same circles, pressing 1.2 N, over 4 s.
std::shared_ptr<const guidance::ReferenceTrajectory> circleReference() {
  HapticProfile expert;
  for (int i = 0; i <= 4000; ++i) {
    Sample s;
    s.t_s = i * 1e-3;
    const double a = 2 * 3.141592653589793 * s.t_s;
    s.p_WT = Vec3(0.015 * std::cos(a), 0.015 * std::sin(a), -0.002);
    s.f_user_W = Vec3(0.1 * std::sin(a), -0.1 * std::cos(a), -1.2);
    s.pen_down = s.in_contact = true;
    expert.append(s);
  }
  return std::make_shared<guidance::ReferenceTrajectory>(expert, 1000.0);
}

void BM_ServoTickFullPipeline(benchmark::State& state) {
  device::CircleHand hand(Vec3::Zero(), 0.015, 1.0, 1.0);
  device::SimulatedDevice device(device::SimulatedPenParams{}, &hand);
  render::PaperRenderer paper(render::PaperParams{}, render::HeightField::paperGrain(0.16, 512, 1e-5, 5e-4, 2));
  guidance::GuidanceConfig config{.mode = guidance::TrainingMode::kForceControl};
  config.playback.end_hold_s = 1e9;  // keep guiding however long the benchmark runs
  guidance::TrainingGuidance guidance(circleReference(), config);
  servo::ServoLoop loop(device, servo::ServoConfig{});
  loop.setWorld(&paper);
  loop.setGuidance(&guidance);
  session::Recorder recorder(loop.samples(), session::RecorderConfig{}, ProfileMetadata{});
  recorder.start();
  std::int64_t ticks = 0;
  for (auto _ : state) {
    loop.runSimulated(1000);
    recorder.drain();
    ticks += 1000;
    if (recorder.profile().size() > 1'000'000) {  // keep memory bounded on long runs
      state.PauseTiming();
      (void)recorder.takeProfile();
      state.ResumeTiming();
    }
  }
  state.SetItemsProcessed(ticks);
  state.counters["time_per_tick"] =
      benchmark::Counter(static_cast<double>(ticks), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

BENCHMARK(BM_ServoTickFullPipeline)->Unit(benchmark::kMicrosecond);

}  // namespace
