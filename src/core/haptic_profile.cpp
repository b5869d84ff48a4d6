#include "hattr/core/haptic_profile.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/chrono.h>

#include "hattr/core/error.hpp"

namespace hattr {

HapticProfile::HapticProfile(ProfileMetadata metadata, RawChannels raw)
    : metadata_(std::move(metadata)), raw_(raw) {}

std::string_view firstNonFiniteChannel(const Sample& sample, const RawChannels& raw) {
  // Fast path: everything finite (the common case, once per recorded sample).
  const bool vectors_finite = std::isfinite(sample.t_s) && sample.p_WT.allFinite() && sample.v_WT.allFinite() &&
                              sample.f_user_W.allFinite() && sample.f_cmd_W.allFinite() && sample.f_guide_W.allFinite();
  const bool raw_finite = (!raw.pressure || std::isfinite(sample.pressure_raw)) &&
                          (!raw.tilt || (std::isfinite(sample.tilt_azimuth_rad) && std::isfinite(sample.tilt_altitude_rad)));
  if (vectors_finite && raw_finite) return {};
  // Slow path: name the first bad channel.
  for (const auto& info : allChannels()) {
    if (info.derived || needsRawChannel(info.channel, raw)) continue;
    if (!std::isfinite(channelValue(sample, info.channel))) return info.name;
  }
  return {};
}

void HapticProfile::append(const Sample& sample) {
  // Reject non-finite values and time that does not move forward.
  const std::string_view bad = firstNonFiniteChannel(sample, raw_);
  HATTR_THROW_UNLESS(bad.empty(), "sample {}: channel {}: expected a finite number, got {}",
                     samples_.size(), bad, channelValue(sample, *channelFromName(bad)));
  HATTR_THROW_UNLESS(samples_.empty() || sample.t_s > samples_.back().t_s,
                     "sample {}: time must increase strictly: expected > {} s, got {} s",
                     samples_.size(), samples_.back().t_s, sample.t_s);
  samples_.push_back(sample);
}

HapticProfile HapticProfile::fromSamples(ProfileMetadata metadata, RawChannels raw, std::vector<Sample> samples,
                                        bool derive_velocity) {
  HapticProfile profile(std::move(metadata), raw);
  profile.reserve(samples.size());
  for (const Sample& s : samples) profile.append(s);
  // Positions finite and times strictly increasing (checked): the differences are finite.
  if (derive_velocity) {
    fillVelocityByFiniteDifferences(samples);
    profile.samples_ = std::move(samples);
  }
  return profile;
}

double HapticProfile::duration_s() const {
  return samples_.size() < 2 ? 0.0 : samples_.back().t_s - samples_.front().t_s;
}

double HapticProfile::measuredRate_hz() const {
  const double duration = duration_s();
  return duration > 0.0 ? static_cast<double>(samples_.size() - 1) / duration : 0.0;
}

std::size_t HapticProfile::penDownCount() const {
  return static_cast<std::size_t>(
      std::count_if(samples_.begin(), samples_.end(), [](const Sample& s) { return s.pen_down; }));
}

bool HapticProfile::hasChannel(Channel channel) const { return !needsRawChannel(channel, raw_); }

std::vector<double> HapticProfile::channel(Channel channel) const {
  HATTR_THROW_UNLESS(hasChannel(channel), "channel {}: this profile has no {} data",
                     channelInfo(channel).name, channelInfo(channel).name);
  std::vector<double> values(samples_.size());
  std::transform(samples_.begin(), samples_.end(), values.begin(),
                 [channel](const Sample& s) { return channelValue(s, channel); });
  return values;
}

std::vector<double> HapticProfile::channel(std::string_view name) const {
  const auto found = channelFromName(name);
  HATTR_THROW_UNLESS(found.has_value(), "unknown channel \"{}\": expected one of {}", name,
                     channelNameList());
  return channel(*found);
}

ChannelRange HapticProfile::range(Channel channel) const {
  HATTR_THROW_UNLESS(!samples_.empty(), "channel {}: the profile has no samples",
                     channelInfo(channel).name);
  const std::vector<double> values = this->channel(channel);
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return {*lo, *hi};
}

bool operator==(const HapticProfile& a, const HapticProfile& b) {
  return a.metadata_ == b.metadata_ && a.raw_ == b.raw_ && a.samples_ == b.samples_;
}

std::string utcNowIso8601() {
  const auto now = std::chrono::floor<std::chrono::seconds>(std::chrono::system_clock::now());
  return fmt::format("{:%Y-%m-%dT%H:%M:%SZ}", fmt::gmtime(std::chrono::system_clock::to_time_t(now)));
}

Vec3 centreOnPaper(std::vector<Sample>& samples) {
  const bool any_down = std::any_of(samples.begin(), samples.end(), [](const Sample& s) { return s.pen_down; });
  Vec3 low = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 high = -low;
  for (const Sample& s : samples) {
    if (any_down && !s.pen_down) continue;
    low = low.cwiseMin(s.p_WT);
    high = high.cwiseMax(s.p_WT);
  }
  if (!low.allFinite()) return Vec3::Zero();  // no samples
  const Vec3 shift(-0.5 * (low.x() + high.x()), -0.5 * (low.y() + high.y()), 0.0);
  for (Sample& s : samples) s.p_WT += shift;
  return shift;
}

}  // namespace hattr

namespace hattr {

void fillVelocityByFiniteDifferences(std::span<Sample> samples) {
  const std::size_t n = samples.size();
  if (n < 2) {
    for (auto& s : samples) s.v_WT.setZero();
    return;
  }
  // Ends: one-sided first differences.
  samples.front().v_WT = (samples[1].p_WT - samples[0].p_WT) / (samples[1].t_s - samples[0].t_s);
  samples.back().v_WT =
      (samples[n - 1].p_WT - samples[n - 2].p_WT) / (samples[n - 1].t_s - samples[n - 2].t_s);
  // Inside: the derivative of the parabola through three neighbours (non-uniform steps).
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double h0 = samples[i].t_s - samples[i - 1].t_s;
    const double h1 = samples[i + 1].t_s - samples[i].t_s;
    const Vec3 d0 = (samples[i].p_WT - samples[i - 1].p_WT) / h0;
    const Vec3 d1 = (samples[i + 1].p_WT - samples[i].p_WT) / h1;
    samples[i].v_WT = (h1 * d0 + h0 * d1) / (h0 + h1);
  }
}

}  // namespace hattr
