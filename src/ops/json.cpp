#include "hattr/ops/json.hpp"

#include "hattr/guidance/strategy_catalog.hpp"

#include <string>

namespace hattr::ops {

nlohmann::json profileSummaryJson(const HapticProfile& profile) {
  const ProfileMetadata& meta = profile.metadata();
  nlohmann::json json;
  json["samples"] = profile.size();
  json["pen_down_samples"] = profile.penDownCount();
  json["duration_s"] = profile.duration_s();
  json["rate_hz"] = profile.measuredRate_hz();
  json["nominal_rate_hz"] = meta.nominal_rate_hz;

  // Every channel the profile has, with its SI unit and range.
  nlohmann::json channels = nlohmann::json::object();
  for (const auto& info : allChannels()) {
    if (!profile.hasChannel(info.channel) || profile.empty()) continue;
    const ChannelRange range = profile.range(info.channel);
    channels[std::string(info.name)] = {{"unit", info.unit}, {"min", range.min}, {"max", range.max}};
  }
  json["channels"] = channels;

  nlohmann::json metadata = {{"subject", meta.subject}, {"skill", meta.skill},
                             {"device", meta.device},   {"source", meta.source},
                             {"created_utc", meta.created_utc}};
  for (const auto& [key, value] : meta.extra) metadata[key] = value;
  json["metadata"] = metadata;
  return json;
}

nlohmann::json physicalEventsJson(const session::PhysicalEvents& events) {
  const auto one = [](const session::PhysicalEvent& e, const char* worst_name) {
    return nlohmann::json{{"count", e.count}, {"first_s", e.first_s}, {worst_name, e.worst}};
  };
  return {{"penetration", one(events.penetration, "deepest_m")},
          {"force_saturation", one(events.saturation, "longest_s")},
          {"workspace", one(events.workspace, "farthest_m")}};
}

nlohmann::json percentilesUsJson(const DurationHistogram& histogram) {
  const auto us = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-3; };
  return {{"p50", us(histogram.percentile_ns(0.50))},
          {"p99", us(histogram.percentile_ns(0.99))},
          {"p99_9", us(histogram.percentile_ns(0.999))},
          {"max", us(histogram.max_ns())},
          {"count", histogram.count()}};
}

nlohmann::json dropsJson(const wire::DropCounts& drops) {
  nlohmann::json json = nlohmann::json::object();
  for (std::size_t r = 0; r < drops.size(); ++r) {
    json[std::string(wire::dropReasonName(static_cast<wire::DropReason>(r)))] = drops[r];
  }
  return json;
}

nlohmann::json linkJson(const device::LinkStats& link) {
  const double expected = static_cast<double>(link.states_received + link.states_lost);
  return {{"rtt_us", percentilesUsJson(link.rtt)},
          {"state_age_us", percentilesUsJson(link.state_age)},
          {"clock_offset_us", static_cast<double>(link.clock_offset_ns) * 1e-3},
          {"commands_sent", link.commands_sent},
          {"states_received", link.states_received},
          {"states_lost", link.states_lost},
          {"loss", expected > 0.0 ? static_cast<double>(link.states_lost) / expected : 0.0},
          {"states_late", link.states_late},
          {"held_reads", link.held_reads},
          {"disconnected_reads", link.disconnected_reads},
          {"reconnects", link.reconnects},
          {"drops", dropsJson(link.drops)}};
}

nlohmann::json realtimeReportJson(const servo::RealtimeReport& report) {
  return {{"fifo", report.fifo},
          {"memory_locked", report.memory_locked},
          {"pinned", report.pinned},
          {"timer_slack_minimal", report.timer_slack_minimal},
          {"notes", report.notes}};
}

nlohmann::json verdictsJson(const servo::LoopJudgement& judgement) {
  nlohmann::json figures = nlohmann::json::array();
  for (const auto& f : judgement.figures) {
    figures.push_back({{"figure", f.name},
                       {"value", f.value},
                       {"unit", f.unit},
                       {"verdict", std::string(servo::verdictName(f.verdict))},
                       {"rule", f.rule}});
  }
  return figures;
}

nlohmann::json strategiesJson() {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& s : guidance::strategyCatalog()) {
    nlohmann::json parameters = nlohmann::json::array();
    for (const auto& p : s.parameters) {
      if (p.choices.empty()) {
        parameters.push_back({{"name", p.name}, {"unit", p.unit}, {"default", p.default_value}, {"min", p.min},
                              {"max", p.max}, {"meaning", p.meaning}});
      } else {
        parameters.push_back({{"name", p.name}, {"default", p.choices.at(static_cast<std::size_t>(p.default_value))},
                              {"choices", p.choices}, {"meaning", p.meaning}});
      }
    }
    list.push_back({{"name", guidance::strategyName(s.mode)}, {"plain_name", s.plain_name},
                    {"description", s.description}, {"source", s.source}, {"mentored", s.mentored},
                    {"scheduled", guidance::isScheduled(s.mode)}, {"parameters", parameters}});
  }
  return list;
}

}  // namespace hattr::ops
