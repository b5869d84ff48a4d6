#pragma once
/// The servo check (`hattr servo-check`) as one library call: the platform's floor (a bare
/// sleep loop at the rate) and then the full pipeline (a hand writing circles on the paper
/// through the device, the safety path, a consumer draining the samples) for the same time,
/// with each figure's verdict (docs/realtime.md). Front ends only parse, call and show.
///
/// Threads: runServoCheck blocks for twice `seconds`; it starts the loop's thread and a
/// consumer (and the floor's thread when progress is shown), and joins them before returning.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/core/histogram.hpp"
#include "hattr/device/link_stats.hpp"
#include "hattr/servo/loop_verdict.hpp"
#include "hattr/servo/realtime.hpp"

namespace hattr::ops {

struct ServoCheckOptions {
  double rate_hz = 1000.0;
  double seconds = 5.0;                   ///< each of the two runs [s]
  std::string device = "sim://pen";       ///< a device URI
  std::filesystem::path world;            ///< a world file; empty: the defaults
  servo::RealtimeSettings realtime;
  /// Called on the calling thread about every 0.1 s while a run goes on: which (1: the bare
  /// sleep loop, 2: the servo loop) and the seconds it has run. When set, the floor is measured
  /// on a thread of its own meanwhile.
  std::function<void(int run, double seconds)> progress;
};

struct ServoCheckResult {
  ServoCheckOptions options;
  std::vector<std::string> world_clamps;  ///< what the device's passivity bounds changed in the world
  servo::RealtimeReport realtime;         ///< what the servo thread got
  DurationHistogram floor;                ///< the bare sleep loop's period error
  DurationHistogram period_error;         ///< the servo loop's
  DurationHistogram tick_compute;         ///< the servo loop's work per tick
  servo::LoopFigures figures;             ///< ticks, overruns, faults, link faults, dropped samples, stalls
  std::uint64_t disconnected_ticks = 0;
  std::uint64_t samples_consumed = 0;
  std::optional<device::DeviceLink> link; ///< a device behind a network link
  std::string link_fault;                 ///< the device's last fault, if any
  servo::LoopJudgement judgement;         ///< every figure's verdict and the overall one
  /// The servo loop's p99 period error over the floor's (0 when the floor measured nothing).
  [[nodiscard]] double ratioP99() const noexcept;
  /// {rate_hz, seconds, device, world, world_clamps, realtime, floor, loop, ratio_p99, [link],
  /// verdicts, verdict}: the schema of `hattr servo-check --json`.
  [[nodiscard]] nlohmann::json toJson() const;
};

/// Runs the check. Throws InputError for a bad device URI or world file, hattr::Error when the
/// device cannot be opened or real time is required and refused.
ServoCheckResult runServoCheck(const ServoCheckOptions& options);

}  // namespace hattr::ops
