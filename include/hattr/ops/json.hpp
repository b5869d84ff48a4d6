#pragma once
/// The JSON every front end shows the same way: timing percentiles, drop counts by reason, a
/// network link's figures, what real time the loop got, the verdicts. One writer each, so the
/// CLI, the studio and Python print one schema.

#include <array>
#include <cstdint>

#include <nlohmann/json.hpp>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/core/histogram.hpp"
#include "hattr/device/link_stats.hpp"
#include "hattr/servo/loop_verdict.hpp"
#include "hattr/servo/realtime.hpp"
#include "hattr/session/trial_physics.hpp"
#include "hattr/wire/packet.hpp"

namespace hattr::ops {

/// A profile's summary, as `hattr profile info --json` prints it: samples, pen_down_samples,
/// duration_s, rate_hz, nominal_rate_hz, channels {name: {unit, min, max}}, metadata.
nlohmann::json profileSummaryJson(const HapticProfile& profile);

/// A trial's physical events: each kind {count, first_s, and its worst value} (penetration
/// deepest_m, force_saturation longest_s, workspace farthest_m).
nlohmann::json physicalEventsJson(const session::PhysicalEvents& events);

/// {p50, p99, p99_9, max, count} of a histogram, in µs (count: samples).
nlohmann::json percentilesUsJson(const DurationHistogram& histogram);

/// {reason: count} for every wire::DropReason, zeros included (a fixed schema).
nlohmann::json dropsJson(const wire::DropCounts& drops);

/// A udp:// device's link: round trip, state age, clock offset, packets, loss, late, held and
/// disconnected reads, reconnects, drops.
nlohmann::json linkJson(const device::LinkStats& link);

/// {fifo, memory_locked, pinned, timer_slack_minimal, notes}.
nlohmann::json realtimeReportJson(const servo::RealtimeReport& report);

/// [{figure, value, unit, verdict, rule}].
nlohmann::json verdictsJson(const servo::LoopJudgement& judgement);

/// Every training strategy (guidance::strategyCatalog), as `hattr strategies --json` and
/// Python's hattr.strategies() give it: [{name, plain_name, description, source, mentored,
/// scheduled, parameters}], a number parameter {name, unit, default, min, max, meaning}, a
/// choice {name, default, choices, meaning} (the default a choice's name).
nlohmann::json strategiesJson();

}  // namespace hattr::ops
