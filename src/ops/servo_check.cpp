#include "hattr/ops/servo_check.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <memory>
#include <thread>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/render/paper_renderer.hpp"
#include "hattr/render/world_config.hpp"
#include "hattr/servo/servo_loop.hpp"

namespace hattr::ops {
namespace {

using Clock = std::chrono::steady_clock;

/// Calls `progress(run, seconds passed)` about every 0.1 s until `done()` or `deadline`.
void reportUntil(const ServoCheckOptions& o, int run, const std::function<bool()>& done, Clock::time_point deadline) {
  const auto begin = Clock::now();
  for (auto now = begin; !done() && now < deadline; now = Clock::now()) {
    std::this_thread::sleep_until(std::min(deadline, now + std::chrono::milliseconds(100)));
    const double passed = std::chrono::duration<double>(Clock::now() - begin).count();
    o.progress(run, std::min(passed, o.seconds));
  }
}

// The platform's floor: the same sleeps with nothing to do; on a thread of its own while this
// one reports progress, else here.
DurationHistogram measureFloor(const ServoCheckOptions& o, std::chrono::nanoseconds duration) {
  if (!o.progress) return servo::measureSleepFloor(o.rate_hz, duration, o.realtime);
  DurationHistogram floor;
  std::exception_ptr error;
  std::atomic<bool> done{false};
  {
    std::jthread thread([&] {  // joined at the end of the block, whatever happens
      try {
        floor = servo::measureSleepFloor(o.rate_hz, duration, o.realtime);
      } catch (...) {
        error = std::current_exception();
      }
      done.store(true, std::memory_order_release);
    });
    reportUntil(o, 1, [&] { return done.load(std::memory_order_acquire); }, Clock::time_point::max());
  }
  if (error) std::rethrow_exception(error);
  return floor;
}

}  // namespace

double ServoCheckResult::ratioP99() const noexcept {
  const auto floor_p99 = static_cast<double>(floor.percentile_ns(0.99));
  return floor_p99 > 0.0 ? static_cast<double>(period_error.percentile_ns(0.99)) / floor_p99 : 0.0;
}

nlohmann::json ServoCheckResult::toJson() const {
  nlohmann::json json = {
      {"rate_hz", options.rate_hz},
      {"seconds", options.seconds},
      {"device", options.device},
      {"world", options.world.empty() ? std::string("defaults") : options.world.string()},
      {"world_clamps", world_clamps},
      {"realtime", realtimeReportJson(realtime)},
      {"floor", {{"period_error_us", percentilesUsJson(floor)}}},
      {"loop",
       {{"period_error_us", percentilesUsJson(period_error)},
        {"tick_compute_us", percentilesUsJson(tick_compute)},
        {"ticks", figures.ticks},
        {"samples_consumed", samples_consumed},
        {"overruns", figures.overruns},
        {"dropped_samples", figures.dropped_samples},
        {"faults", figures.faults},
        {"stalls", figures.stalls},
        {"link_faults", figures.link_faults},
        {"disconnected_ticks", disconnected_ticks}}},
      {"ratio_p99", ratioP99()},
  };
  if (link) {
    json["link"] = linkJson(link->stats);
    json["link"]["server_rate_hz"] = link->server_rate_hz;
    json["link"]["fault"] = link_fault;
  }
  json["verdicts"] = verdictsJson(judgement);
  json["verdict"] = std::string(servo::verdictName(judgement.overall));
  return json;
}

ServoCheckResult runServoCheck(const ServoCheckOptions& options) {
  HATTR_THROW_UNLESS(std::isfinite(options.rate_hz) && options.rate_hz >= 1.0 && options.rate_hz <= 10000.0,
                     "servo check: rate: expected 1 to 10000 Hz, got {}", options.rate_hz);
  HATTR_THROW_UNLESS(std::isfinite(options.seconds) && options.seconds >= 0.01 && options.seconds <= 3600.0,
                     "servo check: seconds: expected 0.01 to 3600 s, got {}", options.seconds);
  ServoCheckResult result;
  result.options = options;
  result.options.progress = nullptr;  // a result does not call back
  // The paper first (its relief and texture take a while, under a sanitizer seconds): a network
  // device's session, opened below, then waits for nothing before the loop runs.
  render::WorldConfig world = options.world.empty() ? render::WorldConfig{} : render::loadWorldConfig(options.world);
  auto paper = std::make_unique<render::PaperRenderer>(world.paper, render::buildRelief(world.relief));
  const auto duration = std::chrono::nanoseconds(units::secondsToNanoseconds(options.seconds));
  result.floor = measureFloor(options, duration);

  // Then the full pipeline: a hand writing circles on the paper through the device, the paper
  // clamped to what this device renders passively (made again only if that changed it).
  device::CircleHand hand(Vec3::Zero(), 0.015, 1.0, 1.0);
  const auto device = device::openDevice(options.device, &hand);
  result.world_clamps = render::clampToDevice(world.paper, device->limits(), options.rate_hz);
  world.paper.normal_from_pressure = device->limits().degrees_of_freedom == 2;  // a planar pen on its table
  if (!result.world_clamps.empty() || world.paper.normal_from_pressure) {
    paper = std::make_unique<render::PaperRenderer>(world.paper, paper->relief());
  }
  servo::ServoLoop loop(*device, servo::ServoConfig{.rate_hz = options.rate_hz, .realtime = options.realtime});
  loop.setWorld(paper.get());
  std::atomic<bool> done{false};
  std::jthread consumer([&] {  // drains the samples as the recorder does
    TickSample s;
    while (!done.load(std::memory_order_acquire)) {
      while (loop.samples().tryPop(s)) ++result.samples_consumed;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    while (loop.samples().tryPop(s)) ++result.samples_consumed;
  });
  loop.start();
  const auto end = Clock::now() + duration;
  if (options.progress) {
    reportUntil(options, 2, [] { return false; }, end);
  } else {
    std::this_thread::sleep_until(end);
  }
  loop.stop();
  done.store(true, std::memory_order_release);
  consumer.join();

  // The figures and their verdicts, the link's too for a device behind one.
  result.realtime = loop.realtimeReport();
  result.period_error = loop.periodError();
  result.tick_compute = loop.tickCompute();
  result.figures = servo::figuresOf(loop);
  result.disconnected_ticks = loop.counters().disconnected_ticks.load();
  result.judgement = servo::judgeLoop(result.figures);
  result.link = device->link();
  if (result.link) {
    result.link_fault = device->faultReason();
    servo::judgeLink(result.link->stats, result.judgement);
  }
  return result;
}

}  // namespace hattr::ops
