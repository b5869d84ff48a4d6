#include "hattr/core/channel.hpp"

#include <array>
#include <cmath>
#include <string>

namespace hattr {
namespace {

constexpr std::array kChannels{
    ChannelInfo{Channel::kTime, "t", "s", false},
    ChannelInfo{Channel::kX, "x", "m", false},
    ChannelInfo{Channel::kY, "y", "m", false},
    ChannelInfo{Channel::kZ, "z", "m", false},
    ChannelInfo{Channel::kVx, "vx", "m_per_s", false},
    ChannelInfo{Channel::kVy, "vy", "m_per_s", false},
    ChannelInfo{Channel::kVz, "vz", "m_per_s", false},
    ChannelInfo{Channel::kSpeed, "speed", "m_per_s", true},
    ChannelInfo{Channel::kFx, "fx", "N", false},
    ChannelInfo{Channel::kFy, "fy", "N", false},
    ChannelInfo{Channel::kFz, "fz", "N", false},
    ChannelInfo{Channel::kForceMagnitude, "|f|", "N", true},
    ChannelInfo{Channel::kCmdFx, "cmd_fx", "N", false},
    ChannelInfo{Channel::kCmdFy, "cmd_fy", "N", false},
    ChannelInfo{Channel::kCmdFz, "cmd_fz", "N", false},
    ChannelInfo{Channel::kGuideFx, "guide_fx", "N", false},
    ChannelInfo{Channel::kGuideFy, "guide_fy", "N", false},
    ChannelInfo{Channel::kGuideFz, "guide_fz", "N", false},
    ChannelInfo{Channel::kContact, "contact", "bool", false},
    ChannelInfo{Channel::kPenDown, "pen_down", "bool", false},
    ChannelInfo{Channel::kPressure, "pressure", "raw", false},
    ChannelInfo{Channel::kAzimuth, "azimuth", "rad", false},
    ChannelInfo{Channel::kAltitude, "altitude", "rad", false},
};

std::string makeNameList() {
  std::string names;
  for (const auto& info : kChannels) {
    if (!names.empty()) names += ", ";
    names += info.name;
  }
  return names;
}

}  // namespace

std::span<const ChannelInfo> allChannels() { return kChannels; }

const ChannelInfo& channelInfo(Channel channel) {
  return kChannels[static_cast<std::size_t>(channel)];
}

std::optional<Channel> channelFromName(std::string_view name) {
  if (name == "fmag") return Channel::kForceMagnitude;
  for (const auto& info : kChannels) {
    if (info.name == name) return info.channel;
  }
  return std::nullopt;
}

std::string_view channelNameList() {
  static const std::string names = makeNameList();
  return names;
}

bool needsRawChannel(Channel channel, const RawChannels& have) {
  switch (channel) {
    case Channel::kPressure: return !have.pressure;
    case Channel::kAzimuth:
    case Channel::kAltitude: return !have.tilt;
    default: return false;
  }
}

double channelValue(const Sample& s, Channel channel) {
  switch (channel) {
    case Channel::kTime: return s.t_s;
    case Channel::kX: return s.p_WT.x();
    case Channel::kY: return s.p_WT.y();
    case Channel::kZ: return s.p_WT.z();
    case Channel::kVx: return s.v_WT.x();
    case Channel::kVy: return s.v_WT.y();
    case Channel::kVz: return s.v_WT.z();
    case Channel::kSpeed: return s.v_WT.norm();
    case Channel::kFx: return s.f_user_W.x();
    case Channel::kFy: return s.f_user_W.y();
    case Channel::kFz: return s.f_user_W.z();
    case Channel::kForceMagnitude: return s.f_user_W.norm();
    case Channel::kCmdFx: return s.f_cmd_W.x();
    case Channel::kCmdFy: return s.f_cmd_W.y();
    case Channel::kCmdFz: return s.f_cmd_W.z();
    case Channel::kGuideFx: return s.f_guide_W.x();
    case Channel::kGuideFy: return s.f_guide_W.y();
    case Channel::kGuideFz: return s.f_guide_W.z();
    case Channel::kContact: return s.in_contact ? 1.0 : 0.0;
    case Channel::kPenDown: return s.pen_down ? 1.0 : 0.0;
    case Channel::kPressure: return s.pressure_raw;
    case Channel::kAzimuth: return s.tilt_azimuth_rad;
    case Channel::kAltitude: return s.tilt_altitude_rad;
  }
  return std::nan("");
}

void setChannelValue(Sample& s, Channel channel, double v) {
  switch (channel) {
    case Channel::kTime: s.t_s = v; break;
    case Channel::kX: s.p_WT.x() = v; break;
    case Channel::kY: s.p_WT.y() = v; break;
    case Channel::kZ: s.p_WT.z() = v; break;
    case Channel::kVx: s.v_WT.x() = v; break;
    case Channel::kVy: s.v_WT.y() = v; break;
    case Channel::kVz: s.v_WT.z() = v; break;
    case Channel::kFx: s.f_user_W.x() = v; break;
    case Channel::kFy: s.f_user_W.y() = v; break;
    case Channel::kFz: s.f_user_W.z() = v; break;
    case Channel::kCmdFx: s.f_cmd_W.x() = v; break;
    case Channel::kCmdFy: s.f_cmd_W.y() = v; break;
    case Channel::kCmdFz: s.f_cmd_W.z() = v; break;
    case Channel::kGuideFx: s.f_guide_W.x() = v; break;
    case Channel::kGuideFy: s.f_guide_W.y() = v; break;
    case Channel::kGuideFz: s.f_guide_W.z() = v; break;
    case Channel::kContact: s.in_contact = v != 0.0; break;
    case Channel::kPenDown: s.pen_down = v != 0.0; break;
    case Channel::kPressure: s.pressure_raw = v; break;
    case Channel::kAzimuth: s.tilt_azimuth_rad = v; break;
    case Channel::kAltitude: s.tilt_altitude_rad = v; break;
    case Channel::kSpeed:
    case Channel::kForceMagnitude: break;  // derived, never a column
  }
}

}  // namespace hattr
