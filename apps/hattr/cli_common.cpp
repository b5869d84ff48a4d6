#include "cli_common.hpp"

#include <iostream>

#include <fmt/format.h>

namespace hattr::cli {

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

std::string profileSummaryText(const HapticProfile& profile) {
  const ProfileMetadata& meta = profile.metadata();
  std::string text = fmt::format(
      "samples     {} ({} pen down)\nduration    {:.4f} s\nrate        {:.2f} Hz measured, {} Hz nominal\n",
      profile.size(), profile.penDownCount(), profile.duration_s(), profile.measuredRate_hz(),
      meta.nominal_rate_hz);
  text += fmt::format("subject     {}\nskill       {}\ndevice      {}\nsource      {}\ncreated     {}\n",
                      meta.subject, meta.skill, meta.device, meta.source, meta.created_utc);
  for (const auto& [key, value] : meta.extra) text += fmt::format("{:<11} {}\n", key, value);
  text += fmt::format("\n{:<10} {:>8} {:>14} {:>14}\n", "channel", "unit", "min", "max");
  for (const auto& info : allChannels()) {
    if (!profile.hasChannel(info.channel) || profile.empty()) continue;
    const ChannelRange range = profile.range(info.channel);
    text += fmt::format("{:<10} {:>8} {:>14.6g} {:>14.6g}\n", info.name, info.unit, range.min, range.max);
  }
  return text;
}

void printJson(const nlohmann::json& json) { std::cout << json.dump(2) << '\n'; }

}  // namespace hattr::cli
