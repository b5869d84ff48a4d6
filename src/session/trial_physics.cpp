#include "hattr/session/trial_physics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/core/error.hpp"

namespace hattr::session {
namespace {

// Counts the episodes of one condition over the samples: an episode begins at the first sample
// where it holds and ends at the next where it does not. `worst` keeps the largest value seen in
// a counted episode, or with `min_span_s` > 0 (an episode counts only once it has lasted that
// long) the longest span.
class EpisodeCounter {
 public:
  explicit EpisodeCounter(double min_span_s = 0.0) : min_span_s_(min_span_s) {}

  void add(double t_s, bool holds, double value) {
    if (!holds) {
      open_ = false;
      return;
    }
    if (!open_) {
      open_ = true;
      counted_ = false;
      begin_s_ = t_s;
    }
    const double span = t_s - begin_s_;
    if (!counted_ && (min_span_s_ <= 0.0 || span > min_span_s_)) {
      counted_ = true;
      ++event_.count;
      if (event_.first_s < 0.0) event_.first_s = begin_s_;
    }
    if (counted_) event_.worst = std::max(event_.worst, min_span_s_ > 0.0 ? span : value);
  }

  [[nodiscard]] const PhysicalEvent& event() const { return event_; }

 private:
  double min_span_s_;
  bool open_ = false;
  bool counted_ = false;
  double begin_s_ = 0.0;
  PhysicalEvent event_;
};

// How far a point lies outside the box [m] (0 inside).
double distanceOutside(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  const Vec3 below = (lo - p).cwiseMax(0.0);
  const Vec3 above = (p - hi).cwiseMax(0.0);
  return (below + above).norm();
}

std::string phrase(const PhysicalEvent& e, const std::string& what) {
  const std::string times = e.count > 1 ? fmt::format(", {} times", e.count) : std::string();
  return fmt::format("{} at {:.3f} s{}", what, e.first_s, times);
}

std::string metadataValue(const PhysicalEvent& e) {
  return fmt::format("{} first {} worst {}", e.count, e.first_s, e.worst);
}

}  // namespace

PhysicalEvents judgeRecording(const HapticProfile& profile, const DeviceLimits& limits, double force_limit_N,
                              const render::HeightField& relief, const PhysicalBounds& bounds) {
  EpisodeCounter penetration;
  EpisodeCounter saturation(bounds.saturation_s);
  EpisodeCounter workspace;
  const double at_limit_N = bounds.saturation_fraction * force_limit_N;
  for (const Sample& s : profile.samples()) {
    const double depth = relief.heightAt(s.p_WT.x(), s.p_WT.y()) - s.p_WT.z();
    penetration.add(s.t_s, depth > bounds.paper_thickness_m, depth);
    // The device at its limit holding up the paper: the paper alone asks for the limit or more.
    const bool at_limit = force_limit_N > 0.0 && s.f_cmd_W.norm() >= at_limit_N && s.f_user_W.norm() >= at_limit_N;
    saturation.add(s.t_s, at_limit, 0.0);
    const double outside = distanceOutside(s.p_WT, limits.workspace_min_m, limits.workspace_max_m);
    workspace.add(s.t_s, outside > 0.0, outside);
  }
  return {penetration.event(), saturation.event(), workspace.event()};
}

std::string describePhysicalEvents(const PhysicalEvents& events) {
  std::vector<std::string> parts;
  if (events.penetration.count > 0) {
    parts.push_back(phrase(events.penetration,
                           fmt::format("the pen {:.1f} mm under the paper", events.penetration.worst * 1e3)));
  }
  if (events.saturation.count > 0) {
    parts.push_back(phrase(events.saturation,
                           fmt::format("the device at its force limit for {:.3f} s", events.saturation.worst)));
  }
  if (events.workspace.count > 0) {
    parts.push_back(phrase(events.workspace, fmt::format("the pen {:.1f} mm outside the device's workspace",
                                                         events.workspace.worst * 1e3)));
  }
  return fmt::format("{}", fmt::join(parts, " · "));
}

// The peak force against the continuous force, and the span of each axis against the
// workspace's; the remedy in each sentence.
std::vector<std::string> renderabilityProblems(const HapticProfile& profile, const DeviceLimits& limits) {
  std::vector<std::string> problems;
  if (profile.empty()) return problems;
  const Sample* strongest = &profile.samples().front();
  Vec3 low = strongest->p_WT;
  Vec3 high = strongest->p_WT;
  for (const Sample& s : profile.samples()) {
    if (s.f_user_W.norm() > strongest->f_user_W.norm()) strongest = &s;
    low = low.cwiseMin(s.p_WT);
    high = high.cwiseMax(s.p_WT);
  }
  const double peak_N = strongest->f_user_W.norm();
  // (Rounding aside: a tablet's full scale at the continuous force resolves into the same norm.)
  if (peak_N > limits.continuous_force_N * (1.0 + 1e-9)) {
    // The largest scale that fits, rounded down to a hundredth.
    const double scale = std::floor(100.0 * limits.continuous_force_N / peak_N) / 100.0;
    problems.push_back(fmt::format(
        "it presses up to {:.2f} N (at {:.3f} s), more than the device's continuous force of {:.2f} N: the device "
        "cannot hold the paper up against it and the pen would sink through; expected at most {:.2f} N: import it again "
        "with a smaller pressure full scale (--calibration, pressure_max_N: docs/file-formats.md) or scale its forces "
        "with `hattr profile convert IN OUT --scale-force {:.2f}`",
        peak_N, strongest->t_s, limits.continuous_force_N, limits.continuous_force_N, scale));
  }
  const Vec3 span = high - low;
  const Vec3 room = limits.workspace_max_m - limits.workspace_min_m;
  constexpr const char* kAxes[] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    if (span[axis] > room[axis]) {
      problems.push_back(fmt::format(
          "it spans {:.1f} mm along {}, more than the device's workspace of {:.1f} mm: expected a profile that fits; "
          "write it smaller or use a device with a larger workspace",
          span[axis] * 1e3, kAxes[axis], room[axis] * 1e3));
    } else if (low[axis] < limits.workspace_min_m[axis] || high[axis] > limits.workspace_max_m[axis]) {
      // It fits, elsewhere: tablet data keeps the tablet's corner as its origin.
      problems.push_back(fmt::format(
          "it reaches {} = {:.1f} to {:.1f} mm, outside the device's workspace of {:.1f} to {:.1f} mm: expected a "
          "profile on the paper; move it there with `hattr profile convert IN OUT --centre`",
          kAxes[axis], low[axis] * 1e3, high[axis] * 1e3, limits.workspace_min_m[axis] * 1e3,
          limits.workspace_max_m[axis] * 1e3));
    }
  }
  return problems;
}

void checkRenderable(const HapticProfile& profile, const DeviceLimits& limits, std::string_view what) {
  const std::vector<std::string> problems = renderabilityProblems(profile, limits);
  if (!problems.empty()) throw InputError(fmt::format("{}: {}", what, fmt::join(problems, "; ")));
}

void notePhysicalEvents(const PhysicalEvents& events, ProfileMetadata& metadata) {
  if (events.penetration.count > 0) metadata.extra["physical_penetration"] = metadataValue(events.penetration);
  if (events.saturation.count > 0) metadata.extra["physical_force_saturation"] = metadataValue(events.saturation);
  if (events.workspace.count > 0) metadata.extra["physical_workspace"] = metadataValue(events.workspace);
}

}  // namespace hattr::session
