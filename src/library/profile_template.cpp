// DTW barycenter averaging of a person's recordings into a template, and library: references.

#include "hattr/library/profile_template.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/library/profile_library.hpp"

namespace hattr::library {

namespace {

/// The alignment channels of samples: x, y (and |f|), each divided by its scale.
std::vector<std::vector<double>> alignmentChannels(const std::vector<Sample>& samples, bool force, const double* scale) {
  std::vector<std::vector<double>> c(force ? 3 : 2, std::vector<double>(samples.size()));
  for (std::size_t i = 0; i < samples.size(); ++i) {
    c[0][i] = samples[i].p_WT.x() / scale[0];
    c[1][i] = samples[i].p_WT.y() / scale[1];
    if (force) c[2][i] = samples[i].f_user_W.norm() / scale[2];
  }
  return c;
}

/// Each channel's standard deviation over every sample of every recording (1 when it is 0).
std::array<double, 3> channelScales(const std::vector<std::vector<Sample>>& recordings) {
  std::array<double, 3> sum{}, sq{};
  double n = 0;
  for (const auto& r : recordings) {
    for (const Sample& s : r) {
      const double v[3] = {s.p_WT.x(), s.p_WT.y(), s.f_user_W.norm()};
      for (int c = 0; c < 3; ++c) sum[c] += v[c], sq[c] += v[c] * v[c];
      n += 1;
    }
  }
  std::array<double, 3> scale{};
  for (int c = 0; c < 3; ++c) {
    const double var = sq[c] / n - (sum[c] / n) * (sum[c] / n);
    scale[c] = var > 1e-24 ? std::sqrt(var) : 1.0;
  }
  return scale;
}

using AlignmentChannels = std::vector<std::vector<double>>;

/// The recording with the least summed DTW cost to the others.
std::size_t medoidOf(const std::vector<AlignmentChannels>& channels, const analysis::DtwOptions& dtw) {
  std::size_t medoid = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < channels.size(); ++a) {
    double sum = 0.0;
    for (std::size_t b = 0; b < channels.size(); ++b) {
      if (a != b) sum += analysis::dtwDependent(channels[a], channels[b], dtw).cost;
    }
    if (sum < best) best = sum, medoid = a;
  }
  return medoid;
}

/// One DBA iteration: every average point becomes the mean of the samples aligned to it; the
/// spreads about the new points are filled in. Returns how far a point moved at most [m].
double dbaIteration(std::vector<Sample>& average, const std::vector<std::vector<Sample>>& series,
                    const std::vector<AlignmentChannels>& channels, const TemplateOptions& options, const double* scale,
                    const analysis::DtwOptions& dtw, std::vector<double>& spread, std::vector<double>& force_spread) {
  const std::size_t n = average.size();
  const auto avg_channels = alignmentChannels(average, options.align_force, scale);
  std::vector<Sample> sum(n);
  std::vector<double> count(n, 0.0), down(n, 0.0);
  std::vector<std::vector<std::pair<std::size_t, std::size_t>>> aligned(n);  // (recording, sample)
  for (std::size_t r = 0; r < series.size(); ++r) {
    for (const auto& step : analysis::dtwDependent(avg_channels, channels[r], dtw).path) {
      const Sample& x = series[r][step.j];
      Sample& acc = sum[step.i];
      acc.p_WT += x.p_WT, acc.v_WT += x.v_WT, acc.f_user_W += x.f_user_W, acc.f_cmd_W += x.f_cmd_W;
      acc.f_guide_W += x.f_guide_W, acc.pressure_raw += x.pressure_raw;
      acc.tilt_azimuth_rad += x.tilt_azimuth_rad, acc.tilt_altitude_rad += x.tilt_altitude_rad;
      count[step.i] += 1.0;
      down[step.i] += x.pen_down ? 1.0 : 0.0;
      aligned[step.i].emplace_back(r, step.j);
    }
  }
  double moved = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double c = count[i];
    Sample next = average[i];
    next.p_WT = sum[i].p_WT / c, next.v_WT = sum[i].v_WT / c, next.f_user_W = sum[i].f_user_W / c;
    next.f_cmd_W = sum[i].f_cmd_W / c, next.f_guide_W = sum[i].f_guide_W / c;
    next.pressure_raw = sum[i].pressure_raw / c;
    next.tilt_azimuth_rad = sum[i].tilt_azimuth_rad / c, next.tilt_altitude_rad = sum[i].tilt_altitude_rad / c;
    next.pen_down = next.in_contact = down[i] * 2.0 > c;
    moved = std::max(moved, (next.p_WT - average[i].p_WT).norm());
    average[i] = next;
    // The spread of what was aligned to it, about the new point.
    double d2 = 0.0, f2 = 0.0;
    for (const auto& [r, j] : aligned[i]) {
      const Sample& x = series[r][j];
      d2 += (x.p_WT - next.p_WT).head<2>().squaredNorm();
      f2 += std::pow(x.f_user_W.norm() - next.f_user_W.norm(), 2);
    }
    spread[i] = std::sqrt(d2 / c);
    force_spread[i] = std::sqrt(f2 / c);
  }
  return moved;
}

}  // namespace

ProfileTemplate buildTemplate(const std::vector<HapticProfile>& recordings, ProfileMetadata metadata,
                              const TemplateOptions& options) {
  HATTR_THROW_UNLESS(recordings.size() >= 2,
                     "template of {} {}: {} recording; expected at least 2 (a template of one is that recording)",
                     metadata.subject, metadata.skill, recordings.size());
  HATTR_THROW_UNLESS(options.max_iterations >= 1, "template: iterations: expected at least 1, got {}",
                     options.max_iterations);
  double mean_duration = 0.0;
  std::vector<std::vector<Sample>> series;
  for (std::size_t r = 0; r < recordings.size(); ++r) {
    HATTR_THROW_UNLESS(recordings[r].size() >= 2 && recordings[r].duration_s() > 0.0,
                       "template of {} {}: recording {} has {} samples over {} s; expected at least 2 over a time",
                       metadata.subject, metadata.skill, r + 1, recordings[r].size(), recordings[r].duration_s());
    mean_duration += recordings[r].duration_s() / static_cast<double>(recordings.size());
    series.push_back(recordings[r].samples());
  }
  const auto scale = channelScales(series);
  std::vector<AlignmentChannels> channels;
  for (const auto& s : series) channels.push_back(alignmentChannels(s, options.align_force, scale.data()));
  analysis::DtwOptions dtw;
  dtw.band_fraction = options.band_fraction;

  // DBA from the medoid, until no point moves by more than 1 µm.
  std::vector<Sample> average = series[medoidOf(channels, dtw)];
  const std::size_t n = average.size();
  const double medoid_t0 = average.front().t_s;
  const double medoid_span = average.back().t_s - medoid_t0;
  ProfileTemplate t;
  t.recordings = recordings.size();
  t.spread_m.assign(n, 0.0);
  t.force_spread_N.assign(n, 0.0);
  dtw.want_path = true;
  for (t.iterations = 1;; ++t.iterations) {
    const double moved = dbaIteration(average, series, channels, options, scale.data(), dtw, t.spread_m, t.force_spread_N);
    if (moved <= 1e-6 || t.iterations == options.max_iterations) break;
  }

  // The medoid's times scaled to the mean duration; velocities from the positions within
  // pen-down runs.
  for (std::size_t i = 0; i < n; ++i) average[i].t_s = (average[i].t_s - medoid_t0) / medoid_span * mean_duration;
  std::size_t start = 0;
  for (std::size_t i = 1; i <= n; ++i) {
    if (i == n || average[i].pen_down != average[start].pen_down) {
      fillVelocityByFiniteDifferences(std::span(average).subspan(start, i - start));
      start = i;
    }
  }
  metadata.source = fmt::format("library-template of {} recordings (DBA, {} iterations)", recordings.size(), t.iterations);
  metadata.created_utc = utcNowIso8601();
  metadata.nominal_rate_hz = static_cast<double>(n - 1) / mean_duration;
  t.profile = HapticProfile(std::move(metadata), recordings.front().rawChannels());
  t.profile.reserve(n);
  for (const Sample& s : average) t.profile.append(s);
  return t;
}

bool isLibraryReference(std::string_view text) { return text.rfind("library:", 0) == 0; }

ProfileTemplate libraryTemplate(std::string_view reference, const TemplateOptions& options) {
  HATTR_THROW_UNLESS(isLibraryReference(reference), "reference \"{}\": expected library:PATH#PERSON/SKILL", reference);
  const std::string_view rest = reference.substr(8);
  const auto hash = rest.rfind('#');
  const auto slash = hash == std::string_view::npos ? std::string_view::npos : rest.find('/', hash);
  HATTR_THROW_UNLESS(hash != std::string_view::npos && hash > 0 && slash != std::string_view::npos && slash > hash + 1 &&
                         slash + 1 < rest.size(),
                     "reference \"{}\": expected library:PATH#PERSON/SKILL (e.g. library:lib.sqlite#U1/signature)",
                     reference);
  const std::string location(rest.substr(0, hash));
  const std::string person(rest.substr(hash + 1, slash - hash - 1));
  const std::string skill(rest.substr(slash + 1));
  const ProfileLibrary lib = ProfileLibrary::open(location, true);
  const auto entries = lib.list({.person = person, .skill = skill, .authenticity = Authenticity::kGenuine});
  HATTR_THROW_UNLESS(!entries.empty(), "reference \"{}\": {} has no genuine {} profiles of {}; `hattr library list -L {} "
                                       "--skill {}` shows who has",
                     reference, location, skill, person, location, skill);
  std::vector<HapticProfile> recordings;
  for (const auto& e : entries) recordings.push_back(lib.profile(e.id));
  try {
    return buildTemplate(recordings, {.subject = person, .skill = skill, .device = recordings.front().metadata().device},
                         options);
  } catch (const InputError& e) {
    throw InputError(fmt::format("reference \"{}\": {}", reference, e.what()));
  }
}

HapticProfile readReference(const std::string& text) {
  return isLibraryReference(text) ? libraryTemplate(text).profile : io::readProfileCsv(text);
}

}  // namespace hattr::library
