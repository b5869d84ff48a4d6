#include "hattr/sim/expert.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/library/profile_template.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/render/world_config.hpp"
#include "minimum_jerk_internal.hpp"

namespace hattr::sim {
namespace {

using detail::minimumJerkBlend;
using detail::minimumJerkBlendRate;
using detail::MinimumJerkSpline;

/// One piece of the expert's timeline.
struct Piece {
  enum class Kind { kHold, kVertical, kMove, kTransit };
  Kind kind = Kind::kHold;
  double start_s = 0.0;
  double duration_s = 0.0;
  bool pen_down = false;
  Vec2 from = Vec2::Zero();   // hold, vertical: the point; transit: the start
  Vec2 to = Vec2::Zero();     // transit: the end
  double z_from_m = 0.0;      // hold, vertical
  double z_to_m = 0.0;        // vertical
  double lift_m = 0.0;        // transit: the height at mid-way
  std::shared_ptr<const MinimumJerkSpline> path;  // move: on normalized time [0, 1]
};

/// The pen-down interval of one stroke, for the force plan.
struct ForceInterval {
  double down_s = 0.0;
  double up_s = 0.0;
};

/// A smooth bump for the pen's height in a transit: 0 at both ends with zero velocity and
/// acceleration, 1 mid-way (64·s³(1 − s)³).
double liftBump(double s) { return 64.0 * std::pow(s * (1.0 - s), 3); }
double liftBumpRate(double s) { return 192.0 * std::pow(s * (1.0 - s), 2) * (1.0 - 2.0 * s); }

/// Splits a stroke's via points at corners sharper than `corner_rad` into rest-to-rest
/// sub-movements (each keeps the corner point as its end and the next one's start).
std::vector<std::vector<Vec2>> splitAtCorners(const std::vector<Vec2>& points, double corner_rad) {
  std::vector<std::vector<Vec2>> parts(1);
  parts.back().push_back(points.front());
  for (std::size_t j = 1; j < points.size(); ++j) {
    parts.back().push_back(points[j]);
    if (j + 1 == points.size()) break;
    const Vec2 in = points[j] - points[j - 1];
    const Vec2 out = points[j + 1] - points[j];
    const double turn = std::atan2(std::abs(in.x() * out.y() - in.y() * out.x()), in.dot(out));
    if (turn > corner_rad) parts.push_back({points[j]});
  }
  return parts;
}

double polylineLength(const std::vector<Vec2>& points) {
  double length = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  return length;
}

/// The largest of f(s) over s in [0, 1], sampled finely.
template <typename F>
double sampledMax(F f) {
  constexpr int kSteps = 2000;
  double best = 0.0;
  for (int i = 0; i <= kSteps; ++i) best = std::max(best, f(static_cast<double>(i) / kSteps));
  return best;
}

void checkRange(double value, double lo, double hi, const char* name, const char* unit) {
  HATTR_THROW_UNLESS(std::isfinite(value) && value >= lo && value <= hi,
                     "expert configuration: {}: expected a value in [{}, {}] {}, got {}", name, lo, hi, unit, value);
}

}  // namespace

void validateExpertConfig(const ExpertConfig& c) {
  checkRange(c.rate_hz, 100.0, 10'000.0, "rate_hz", "Hz");
  checkRange(c.peak_speed_m_per_s, 0.01, 0.5, "peak_speed_m_per_s", "m/s");
  checkRange(c.isochrony_exponent, 0.0, 1.0, "isochrony_exponent", "");
  checkRange(c.corner_angle_rad, 0.01, std::numbers::pi, "corner_angle_rad", "rad");
  checkRange(c.lift_height_m, 0.0005, 0.02, "lift_height_m", "m");
  checkRange(c.min_transit_s, 0.01, 5.0, "min_transit_s", "s");
  checkRange(c.lead_in_s, 0.0, 10.0, "lead_in_s", "s");
  checkRange(c.approach_s, 0.01, 5.0, "approach_s", "s");
  checkRange(c.retreat_s, 0.01, 5.0, "retreat_s", "s");
  checkRange(c.lead_out_s, 0.0, 10.0, "lead_out_s", "s");
  checkRange(c.axial_force_N, 0.01, 5.0, "axial_force_N", "N");
  checkRange(c.touch_down_s, 0.001, 2.0, "touch_down_s", "s");
  checkRange(c.lift_off_s, 0.001, 2.0, "lift_off_s", "s");
  checkRange(c.altitude_rad, 10.0 * std::numbers::pi / 180.0, std::numbers::pi / 2.0, "altitude_rad", "rad");
  checkRange(c.azimuth_rad, -2.0 * std::numbers::pi, 2.0 * std::numbers::pi, "azimuth_rad", "rad");
}

namespace {

/// One sub-movement of a stroke: a minimum-jerk path on normalized time [0, 1].
struct Movement {
  std::shared_ptr<const MinimumJerkSpline> path;
  double length_m;
};

/// Every stroke's sub-movements, and the duration scale c in T = c·L^β, set by the fastest.
std::pair<std::vector<std::vector<Movement>>, double> planMovements(const Glyph& glyph, const ExpertConfig& config) {
  const double beta = config.isochrony_exponent;
  std::vector<std::vector<Movement>> strokes;
  double c = 0.0;  // duration scale in T = c·L^β, set by the fastest movement
  for (std::size_t s = 0; s < glyph.strokes.size(); ++s) {
    const auto& points = glyph.strokes[s].points;
    HATTR_THROW_UNLESS(points.size() >= 2, "expert script for glyph \"{}\": stroke {}: expected at least two points, got {}",
                       glyph.name, s + 1, points.size());
    auto& movements = strokes.emplace_back();
    for (const auto& part : splitAtCorners(points, config.corner_angle_rad)) {
      auto path = std::make_shared<const MinimumJerkSpline>(MinimumJerkSpline::withOptimalTimes(part, 1.0));
      const double length = polylineLength(part);
      const double peak = sampledMax([&](double u) { return path->velocity(u).norm(); });  // per unit time
      // With T = c·L^β the peak speed is peak / (c·L^β); it may not exceed the configured peak.
      c = std::max(c, peak / (config.peak_speed_m_per_s * std::pow(length, beta)));
      movements.push_back({std::move(path), length});
    }
  }
  return {std::move(strokes), c};
}

/// The script's timeline: its pieces in order, and each stroke's pen-down interval.
struct Timeline {
  std::vector<Piece> pieces;
  std::vector<ForceInterval> force_intervals;
  double total_s = 0.0;
};

Timeline buildTimeline(const Glyph& glyph, const ExpertConfig& config,
                       const std::vector<std::vector<Movement>>& strokes, double c) {
  const double beta = config.isochrony_exponent;
  const double lift = config.lift_height_m;
  Timeline timeline;
  std::vector<Piece>& pieces = timeline.pieces;
  double now = 0.0;
  const auto add = [&](Piece piece) {
    piece.start_s = now;
    now += piece.duration_s;
    pieces.push_back(std::move(piece));
  };
  const auto vertical = [&](Vec2 at, double z_from, double z_to, double duration) {
    // A minimum-jerk rise or descent, no faster than the configured peak speed.
    const double needed = 1.875 * std::abs(z_to - z_from) / config.peak_speed_m_per_s;
    add({.kind = Piece::Kind::kVertical, .duration_s = std::max(duration, needed), .from = at, .z_from_m = z_from,
         .z_to_m = z_to});
  };
  const Vec2 first = glyph.strokes.front().points.front();
  if (config.lead_in_s > 0.0) add({.kind = Piece::Kind::kHold, .duration_s = config.lead_in_s, .from = first, .z_from_m = lift});
  vertical(first, lift, 0.0, config.approach_s);
  for (std::size_t s = 0; s < strokes.size(); ++s) {
    const auto& points = glyph.strokes[s].points;
    ForceInterval interval{.down_s = now};
    add({.kind = Piece::Kind::kHold, .duration_s = config.touch_down_s, .pen_down = true, .from = points.front()});
    for (const Movement& m : strokes[s]) {
      add({.kind = Piece::Kind::kMove, .duration_s = c * std::pow(m.length_m, beta), .pen_down = true, .path = m.path});
    }
    add({.kind = Piece::Kind::kHold, .duration_s = config.lift_off_s, .pen_down = true, .from = points.back()});
    interval.up_s = now;
    timeline.force_intervals.push_back(interval);
    if (s + 1 == strokes.size()) break;
    // Pen up to the next stroke's start: the same timing rule, never faster than the peak.
    const Vec2 to = glyph.strokes[s + 1].points.front();
    const double distance = (to - points.back()).norm();
    const double per_unit_time = sampledMax([&](double u) {
      return std::hypot(minimumJerkBlendRate(u) * distance, liftBumpRate(u) * lift);
    });
    const double duration = std::max({c * std::pow(distance, beta), config.min_transit_s,
                                      per_unit_time / config.peak_speed_m_per_s});
    add({.kind = Piece::Kind::kTransit, .duration_s = duration, .from = points.back(), .to = to, .lift_m = lift});
  }
  const Vec2 last = glyph.strokes.back().points.back();
  vertical(last, 0.0, lift, config.retreat_s);
  if (config.lead_out_s > 0.0) add({.kind = Piece::Kind::kHold, .duration_s = config.lead_out_s, .from = last, .z_from_m = lift});
  timeline.total_s = now;
  return timeline;
}

/// The pen's position and velocity at normalized time s of a piece.
void placeOnPiece(const Piece& piece, double s, Sample& sample) {
  switch (piece.kind) {
    case Piece::Kind::kHold:
      sample.p_WT = Vec3(piece.from.x(), piece.from.y(), piece.z_from_m);
      break;
    case Piece::Kind::kVertical: {
      const double dz = piece.z_to_m - piece.z_from_m;
      sample.p_WT = Vec3(piece.from.x(), piece.from.y(), piece.z_from_m + dz * minimumJerkBlend(s));
      sample.v_WT = Vec3(0.0, 0.0, dz * minimumJerkBlendRate(s) / piece.duration_s);
      break;
    }
    case Piece::Kind::kMove: {
      const Vec2 p = piece.path->position(s);
      const Vec2 v = piece.path->velocity(s) / piece.duration_s;
      sample.p_WT = Vec3(p.x(), p.y(), 0.0);
      sample.v_WT = Vec3(v.x(), v.y(), 0.0);
      break;
    }
    case Piece::Kind::kTransit: {
      const Vec2 d = piece.to - piece.from;
      const Vec2 p = piece.from + d * minimumJerkBlend(s);
      const Vec2 v = d * minimumJerkBlendRate(s) / piece.duration_s;
      sample.p_WT = Vec3(p.x(), p.y(), piece.lift_m * liftBump(s));
      sample.v_WT = Vec3(v.x(), v.y(), piece.lift_m * liftBumpRate(s) / piece.duration_s);
      break;
    }
  }
}

}  // namespace

HapticProfile expertScript(const Glyph& glyph, const ExpertConfig& config) {
  validateExpertConfig(config);
  HATTR_THROW_UNLESS(!glyph.strokes.empty(), "expert script for glyph \"{}\": expected at least one stroke, got none",
                     glyph.name);
  const auto [strokes, c] = planMovements(glyph, config);
  const Timeline timeline = buildTimeline(glyph, config, strokes, c);
  const std::vector<Piece>& pieces = timeline.pieces;
  const std::vector<ForceInterval>& force_intervals = timeline.force_intervals;

  // Sample it.
  ProfileMetadata metadata{.subject = "expert", .skill = glyph.name, .source = "sim:expert-script",
                           .nominal_rate_hz = config.rate_hz};
  metadata.extra["generator"] = "hattr::sim::expertScript";
  metadata.extra["peak_speed_m_per_s"] = fmt::format("{}", config.peak_speed_m_per_s);
  metadata.extra["axial_force_N"] = fmt::format("{}", config.axial_force_N);
  HapticProfile script(metadata, RawChannels{.tilt = true});
  const auto count = static_cast<std::size_t>(std::floor(timeline.total_s * config.rate_hz + 1e-9)) + 1;
  script.reserve(count);
  const double normal_share = std::sin(config.altitude_rad);
  std::size_t piece_index = 0;
  std::size_t interval_index = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const double t = static_cast<double>(i) / config.rate_hz;
    while (piece_index + 1 < pieces.size() && t >= pieces[piece_index + 1].start_s) ++piece_index;
    const Piece& piece = pieces[piece_index];
    const double local = std::clamp(t - piece.start_s, 0.0, piece.duration_s);
    Sample sample;
    sample.t_s = t;
    placeOnPiece(piece, local / piece.duration_s, sample);
    sample.pen_down = piece.pen_down;
    sample.in_contact = piece.pen_down;
    if (piece.pen_down) {
      while (interval_index + 1 < force_intervals.size() && t >= force_intervals[interval_index + 1].down_s) {
        ++interval_index;
      }
      const ForceInterval& f = force_intervals[interval_index];
      const double axial = config.axial_force_N * minimumJerkBlend((t - f.down_s) / config.touch_down_s) *
                           minimumJerkBlend((f.up_s - t) / config.lift_off_s);
      sample.f_user_W = Vec3(0.0, 0.0, -axial * normal_share);
    }
    sample.tilt_altitude_rad = config.altitude_rad;
    sample.tilt_azimuth_rad = config.azimuth_rad;
    script.append(sample);
  }
  return script;
}

HapticProfile recordExpert(session::TrialEnvironment& environment, const HapticProfile& script, ProfileMetadata metadata) {
  HATTR_THROW_UNLESS(script.size() >= 2 && script.duration_s() > 0.0,
                     "expert recording: expected a script of at least two samples, got {}", script.size());
  device::ProfileHandScript hand(script);
  session::TrialSetup setup;
  setup.guidance.mode = guidance::TrainingMode::kBasic;
  setup.metadata = std::move(metadata);
  setup.duration_s = script.duration_s();
  return session::runTrial(environment, setup, hand).profile;
}

void recordNamedExperts(session::StudyDefinition& study) {
  if (study.named_experts.empty()) return;
  // The study's own pen when simulated (its limits are the ones its trials meet), else the
  // simulated pen; the study's world and rate.
  const std::string device = device::parseDeviceUri(study.device).scheme == "sim" ? study.device : "sim://pen";
  session::TrialEnvironment environment(device, render::parseWorldConfig(study.world.dump(), "study world"),
                                        study.rate_hz);
  for (const auto& [skill, name] : study.named_experts) {
    // A person's template in a profile library.
    if (library::isLibraryReference(name)) {
      try {
        study.named_expert_profiles[skill] = library::libraryTemplate(name).profile;
      } catch (const InputError& e) {
        throw InputError(fmt::format("experts.{}: {}", skill, e.what()));
      }
      continue;
    }
    // A glyph file (parseStudy made its path whole: it has a '/'), else a built-in glyph: never
    // a file relative to wherever this process runs.
    Glyph glyph;
    try {
      glyph = name.find('/') != std::string::npos ? loadGlyph(name) : findBuiltInGlyph(name);
    } catch (const InputError& e) {
      throw InputError(fmt::format("experts.{}: {}", skill, e.what()));
    }
    study.named_expert_profiles[skill] =
        recordExpert(environment, expertScript(glyph), {.subject = "expert", .skill = skill, .source = "sim:expert"});
  }
}

}  // namespace hattr::sim
