#pragma once
/// A haptic profile — the paper's *haptic attribute*: one person performing one task,
/// as an ordered series of servo-rate samples plus metadata. SI units inside.

#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/channel.hpp"
#include "hattr/core/sample.hpp"

namespace hattr {

struct ProfileMetadata {
  std::string subject;           ///< who performed it ("expert", "S03", a writer id)
  std::string skill;             ///< the skill or character ("na", a signature id)
  std::string device;            ///< device URI or model
  std::string source;            ///< where it came from: "recorded", "import:svc2004 U1S1.TXT", ...
  std::string created_utc;       ///< ISO 8601 creation time, UTC
  double nominal_rate_hz = 0.0;  ///< the rate it was sampled at (0: unknown)
  /// Everything else (mode, trial, phase, calibration, clamped gains...), key → value.
  std::map<std::string, std::string> extra;
  friend bool operator==(const ProfileMetadata&, const ProfileMetadata&) = default;
};

/// Minimum and maximum of one channel over a profile.
struct ChannelRange {
  double min = 0.0;
  double max = 0.0;
};

class HapticProfile {
 public:
  HapticProfile() = default;
  explicit HapticProfile(ProfileMetadata metadata, RawChannels raw = {});

  [[nodiscard]] ProfileMetadata& metadata() { return metadata_; }
  [[nodiscard]] const ProfileMetadata& metadata() const { return metadata_; }
  [[nodiscard]] const RawChannels& rawChannels() const { return raw_; }
  void setRawChannels(const RawChannels& raw) { raw_ = raw; }

  /// Appends a sample. Throws InputError unless its time is finite and strictly after
  /// the last sample's, and every value is finite. Not for the servo thread.
  void append(const Sample& sample);
  void reserve(std::size_t n) { samples_.reserve(n); }
  /// A profile from samples, each checked as append() checks it; with `derive_velocity`, their
  /// velocities are then set from their positions (fillVelocityByFiniteDifferences). For
  /// sources that build all samples first (Python's HapticProfile.from_arrays). Throws
  /// InputError naming the first bad sample. Not for the servo thread.
  static HapticProfile fromSamples(ProfileMetadata metadata, RawChannels raw, std::vector<Sample> samples,
                                   bool derive_velocity);
  void clear() { samples_.clear(); }

  [[nodiscard]] const std::vector<Sample>& samples() const { return samples_; }
  [[nodiscard]] std::size_t size() const { return samples_.size(); }
  [[nodiscard]] bool empty() const { return samples_.empty(); }
  [[nodiscard]] const Sample& operator[](std::size_t i) const { return samples_[i]; }

  /// Last time minus first time [s]; 0 with fewer than two samples.
  [[nodiscard]] double duration_s() const;
  /// Mean sampling rate (samples − 1) / duration [Hz]; 0 with fewer than two samples.
  [[nodiscard]] double measuredRate_hz() const;
  /// Number of samples with the pen down.
  [[nodiscard]] std::size_t penDownCount() const;

  /// True if the profile carries this channel (raw channels only when recorded).
  [[nodiscard]] bool hasChannel(Channel channel) const;
  /// One channel as a series, SI units. Throws InputError if the profile lacks it.
  [[nodiscard]] std::vector<double> channel(Channel channel) const;
  /// The same, by name ("x", "fz", "|f|", ...). Throws InputError for an unknown name.
  [[nodiscard]] std::vector<double> channel(std::string_view name) const;
  /// Minimum and maximum of a channel. Throws InputError if empty or absent.
  [[nodiscard]] ChannelRange range(Channel channel) const;

  friend bool operator==(const HapticProfile& a, const HapticProfile& b);

 private:
  ProfileMetadata metadata_;
  RawChannels raw_;
  std::vector<Sample> samples_;
};

/// Checks that every value of a sample is finite; returns the name of the first
/// non-finite channel, or an empty view when all are finite.
std::string_view firstNonFiniteChannel(const Sample& sample, const RawChannels& raw);

/// Current UTC time as ISO 8601 ("2026-11-21T21:40:00Z").
std::string utcNowIso8601();

}  // namespace hattr

namespace hattr {

/// Sets every sample's velocity from its positions by finite differences (central
/// inside, one-sided at the ends; exact for non-uniform time steps on a parabola).
/// For sources that record only positions (tablets, hand-written files).
void fillVelocityByFiniteDifferences(std::span<Sample> samples);

/// Places writing on the paper: moves the centre of the pen-down points' box in the paper
/// plane (of all points when none is down) to W's origin, the paper's centre. Returns the
/// shift applied [m] (z = 0). For tablet data, whose origin is a corner of the tablet.
Vec3 centreOnPaper(std::vector<Sample>& samples);

}  // namespace hattr
