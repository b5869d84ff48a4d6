#pragma once
/// Named channels of a haptic profile: what `profile.channel("fz")`, the CLI and the
/// analysis refer to. Each channel has one SI unit.

#include <optional>
#include <span>
#include <string_view>

#include "hattr/core/sample.hpp"

namespace hattr {

enum class Channel {
  kTime,
  kX, kY, kZ,
  kVx, kVy, kVz, kSpeed,
  kFx, kFy, kFz, kForceMagnitude,
  kCmdFx, kCmdFy, kCmdFz,
  kGuideFx, kGuideFy, kGuideFz,
  kContact, kPenDown,
  kPressure, kAzimuth, kAltitude,
};

/// Which optional raw device channels a profile carries.
struct RawChannels {
  bool pressure = false;  ///< Sample::pressure_raw is meaningful
  bool tilt = false;      ///< Sample::tilt_azimuth_rad and tilt_altitude_rad are meaningful
  friend bool operator==(const RawChannels&, const RawChannels&) = default;
};

struct ChannelInfo {
  Channel channel;
  std::string_view name;   ///< e.g. "fz", "|f|", "pen_down"
  std::string_view unit;   ///< SI unit as written in files: "s", "m", "m_per_s", "N", "bool", "raw", "rad"
  bool derived;            ///< computed from other channels, never stored in files
};

/// Every channel, in file-column order (derived channels included, flagged).
std::span<const ChannelInfo> allChannels();
const ChannelInfo& channelInfo(Channel channel);
/// The channel with this name ("fmag" is accepted as an alias of "|f|"), if any.
std::optional<Channel> channelFromName(std::string_view name);
/// A comma-separated list of every channel name, for error messages and help.
std::string_view channelNameList();
/// True if `channel` needs a raw channel the profile may not have.
bool needsRawChannel(Channel channel, const RawChannels& have);
/// The value of `channel` in one sample, in SI units (flags as 0 or 1).
double channelValue(const Sample& sample, Channel channel);
/// Sets a stored channel of a sample (flags: non-zero is true); derived channels are ignored.
void setChannelValue(Sample& sample, Channel channel, double value);

}  // namespace hattr
