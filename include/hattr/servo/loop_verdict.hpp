#pragma once
/// Verdicts on a finished servo-loop run: each figure PASS, WARN or FAIL against the thresholds
/// of docs/realtime.md ("Verdicts"), for `hattr servo-check` and `hattr devices check`. FAIL is
/// kept for what makes a device unfit to train with whatever the computer does (a latched fault,
/// a dropout, lost samples, a pipeline that cannot keep its rate); what a loaded or untuned
/// computer does to the timing (stalls, jitter, a few overruns) is a WARN, so a check on a busy
/// machine says so without failing.
///
/// Threads: setup code, after the loop stopped.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/device/link_stats.hpp"
#include "hattr/servo/servo_loop.hpp"

namespace hattr::servo {

enum class Verdict { kPass, kWarn, kFail };
/// "PASS", "WARN", "FAIL".
[[nodiscard]] std::string_view verdictName(Verdict verdict) noexcept;

/// One figure and its verdict.
struct JudgedFigure {
  std::string name;    ///< snake_case, as in JSON ("period_error_p99_us")
  double value = 0.0;
  std::string unit;    ///< "", "µs", "%"
  Verdict verdict = Verdict::kPass;
  std::string rule;    ///< the thresholds in words ("PASS ≤ 100 µs (10 % of the period), else WARN")
};

struct LoopJudgement {
  std::vector<JudgedFigure> figures;
  Verdict overall = Verdict::kPass;  ///< the worst figure's
};

/// What a run did, as the verdicts read it.
struct LoopFigures {
  std::uint64_t ticks = 0;
  std::uint64_t overruns = 0;
  std::uint64_t faults = 0;
  std::uint64_t link_faults = 0;
  std::uint64_t dropped_samples = 0;
  std::uint64_t stalls = 0;
  double period_us = 1000.0;
  double period_error_p99_us = 0.0;  ///< measured on a real-time or device clock (0 in simulated time)
};
/// A stopped loop's figures.
[[nodiscard]] LoopFigures figuresOf(const ServoLoop& loop);
/// Judges a run's figures.
[[nodiscard]] LoopJudgement judgeLoop(const LoopFigures& figures);
/// Judges a stopped loop: judgeLoop(figuresOf(loop)).
[[nodiscard]] LoopJudgement judgeLoop(const ServoLoop& loop);
/// Adds the network link's figures of a udp:// device (loss) to `judgement`.
void judgeLink(const device::LinkStats& link, LoopJudgement& judgement);

}  // namespace hattr::servo
