#include "hattr/servo/loop_verdict.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace hattr::servo {
namespace {

// The thresholds (docs/realtime.md, "Verdicts").
constexpr double kJitterShareOfPeriod = 0.10;    // p99 period error up to 10 % of the period: PASS
constexpr double kOverrunShareWarn = 0.001;      // overruns beyond 0.1 % of the ticks: WARN
constexpr double kOverrunShareFail = 0.5;        // beyond half the ticks: the pipeline cannot keep its rate
constexpr double kLinkLossWarn = 0.01;           // states lost beyond 1 %: WARN

/// A count that must be zero: FAIL (or WARN) from the first.
JudgedFigure zeroOr(std::string name, std::uint64_t count, Verdict otherwise, std::string_view what) {
  return {.name = std::move(name),
          .value = static_cast<double>(count),
          .unit = "",
          .verdict = count == 0 ? Verdict::kPass : otherwise,
          .rule = fmt::format("PASS 0, else {} ({})", verdictName(otherwise), what)};
}

void add(LoopJudgement& judgement, JudgedFigure figure) {
  judgement.overall = std::max(judgement.overall, figure.verdict);
  judgement.figures.push_back(std::move(figure));
}

}  // namespace

std::string_view verdictName(Verdict verdict) noexcept {
  switch (verdict) {
    case Verdict::kPass: return "PASS";
    case Verdict::kWarn: return "WARN";
    case Verdict::kFail: return "FAIL";
  }
  return "FAIL";
}

LoopFigures figuresOf(const ServoLoop& loop) {
  const LiveCounters& c = loop.counters();
  return {.ticks = c.ticks.load(),
          .overruns = c.overruns.load(),
          .faults = c.faults.load(),
          .link_faults = c.link_faults.load(),
          .dropped_samples = c.dropped_samples.load(),
          .stalls = c.stalls.load(),
          .period_us = static_cast<double>(loop.period().count()) * 1e-3,
          .period_error_p99_us = static_cast<double>(loop.periodError().percentile_ns(0.99)) * 1e-3};
}

LoopJudgement judgeLoop(const ServoLoop& loop) { return judgeLoop(figuresOf(loop)); }

LoopJudgement judgeLoop(const LoopFigures& f) {
  LoopJudgement j;
  add(j, zeroOr("faults", f.faults, Verdict::kFail, "the safety path latched a fault: zero force"));
  add(j, zeroOr("link_faults", f.link_faults, Verdict::kFail, "the device or its link dropped out: zero force"));
  add(j, zeroOr("dropped_samples", f.dropped_samples, Verdict::kFail, "a recording would miss samples"));
  add(j, zeroOr("stalls", f.stalls, Verdict::kWarn,
                "the computer held the loop beyond its watchdog: force zeroed and ramped in again"));

  // Overruns: ticks that took longer than a period, as a share of the ticks.
  const double overrun_share = static_cast<double>(f.overruns) / static_cast<double>(std::max<std::uint64_t>(1, f.ticks));
  add(j, {.name = "overrun_share_percent",
          .value = 100.0 * overrun_share,
          .unit = "%",
          .verdict = overrun_share > kOverrunShareFail   ? Verdict::kFail
                     : overrun_share > kOverrunShareWarn ? Verdict::kWarn
                                                         : Verdict::kPass,
          .rule = fmt::format("PASS ≤ {} % of the ticks, WARN ≤ {} %, FAIL above (the pipeline cannot keep its rate)",
                              100.0 * kOverrunShareWarn, 100.0 * kOverrunShareFail)});

  // Jitter: the 99th percentile of the period error against the period.
  const double limit_us = kJitterShareOfPeriod * f.period_us;
  add(j, {.name = "period_error_p99_us",
          .value = f.period_error_p99_us,
          .unit = "µs",
          .verdict = f.period_error_p99_us <= limit_us ? Verdict::kPass : Verdict::kWarn,
          .rule = fmt::format("PASS ≤ {:g} µs ({} % of the period), else WARN", limit_us, 100.0 * kJitterShareOfPeriod)});
  return j;
}

void judgeLink(const device::LinkStats& link, LoopJudgement& judgement) {
  const double expected = static_cast<double>(link.states_received + link.states_lost);
  const double loss = expected > 0.0 ? static_cast<double>(link.states_lost) / expected : 0.0;
  add(judgement, {.name = "link_loss_percent",
                  .value = 100.0 * loss,
                  .unit = "%",
                  .verdict = loss <= kLinkLossWarn ? Verdict::kPass : Verdict::kWarn,
                  .rule = fmt::format("PASS ≤ {} % of the states, else WARN", 100.0 * kLinkLossWarn)});
}

}  // namespace hattr::servo
