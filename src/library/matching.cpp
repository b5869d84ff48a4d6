// Feature series of profiles, their distances, verification scores and the exact
// nearest-person search (LB_Keogh, then early-abandoned DTW).

#include "hattr/library/matching.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

#include <fmt/format.h>

#include "analysis/parallel.hpp"
#include "hattr/analysis/dtw.hpp"
#include "hattr/core/error.hpp"

namespace hattr::library {

// ---- Feature sets ----------------------------------------------------------------------------

namespace {

struct FeatureName {
  std::string_view name;
  unsigned bit;
};
constexpr FeatureName kFeatureNames[] = {{"shape", FeatureSet::kShape},
                                         {"force", FeatureSet::kForce},
                                         {"angles", FeatureSet::kAngles},
                                         {"velocity", FeatureSet::kVelocity},
                                         {"timing", FeatureSet::kTiming}};
constexpr unsigned kAllFeatures =
    FeatureSet::kShape | FeatureSet::kForce | FeatureSet::kAngles | FeatureSet::kVelocity | FeatureSet::kTiming;

constexpr std::string_view kChannelNames[kFeatureChannels] = {"x", "y", "force |f|", "azimuth", "altitude", "vx", "vy"};

}  // namespace

std::vector<FeatureChannel> FeatureSet::channels() const {
  std::vector<FeatureChannel> out;
  if (bits & kShape) out.insert(out.end(), {FeatureChannel::kX, FeatureChannel::kY});
  if (bits & kForce) out.push_back(FeatureChannel::kForce);
  if (bits & kAngles) out.insert(out.end(), {FeatureChannel::kAzimuth, FeatureChannel::kAltitude});
  if (bits & kVelocity) out.insert(out.end(), {FeatureChannel::kVx, FeatureChannel::kVy});
  return out;
}

std::string FeatureSet::name() const {
  if (bits == kAllFeatures) return "all";
  std::string out;
  for (const auto& f : kFeatureNames) {
    if (bits & f.bit) out += (out.empty() ? "" : "+") + std::string(f.name);
  }
  return out;
}

FeatureSet parseFeatureSet(std::string_view text) {
  if (text == "all") return {kAllFeatures};
  FeatureSet set{0};
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t plus = std::min(text.find('+', start), text.size());
    const std::string_view part = text.substr(start, plus - start);
    const auto* f = std::find_if(std::begin(kFeatureNames), std::end(kFeatureNames),
                                 [&](const FeatureName& n) { return n.name == part; });
    HATTR_THROW_UNLESS(f != std::end(kFeatureNames),
                       "feature set \"{}\": unknown feature \"{}\"; expected shape, force, angles, velocity or "
                       "timing, joined with '+', or all",
                       text, part);
    set.bits |= f->bit;
    start = plus + 1;
  }
  return set;
}

std::vector<FeatureSet> reportedFeatureSets() {
  return {{FeatureSet::kShape},
          {FeatureSet::kForce},
          {FeatureSet::kAngles},
          {FeatureSet::kVelocity},
          {FeatureSet::kTiming},
          {FeatureSet::kShape | FeatureSet::kForce},
          {FeatureSet::kShape | FeatureSet::kTiming},
          {FeatureSet::kShape | FeatureSet::kForce | FeatureSet::kTiming},
          {kAllFeatures}};
}

void checkFeatureOptions(const FeatureOptions& o) {
  HATTR_THROW_UNLESS(o.length >= 8, "feature length: expected at least 8 steps, got {}", o.length);
  HATTR_THROW_UNLESS(std::isfinite(o.band_fraction) && o.band_fraction > 0.0 && o.band_fraction <= 1.0,
                     "DTW band: expected a fraction in (0, 1], got {}", o.band_fraction);
  HATTR_THROW_UNLESS(std::isfinite(o.timing_weight) && o.timing_weight >= 0.0,
                     "timing weight: expected a finite number >= 0, got {}", o.timing_weight);
}

// ---- Feature series ----------------------------------------------------------------------------

FeatureSeries extractFeatures(const HapticProfile& profile, const FeatureOptions& options, std::string_view where) {
  checkFeatureOptions(options);
  const auto& samples = profile.samples();
  std::vector<std::size_t> down;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (samples[i].pen_down) down.push_back(i);
  }
  HATTR_THROW_UNLESS(down.size() >= 2, "{}: {} pen-down samples; expected at least 2 to compare", where, down.size());

  // Writing time: the steps within strokes; across a lift, one median step within strokes.
  std::vector<double> steps;
  for (std::size_t k = 1; k < down.size(); ++k) {
    if (down[k] == down[k - 1] + 1) steps.push_back(samples[down[k]].t_s - samples[down[k - 1]].t_s);
  }
  double lift_step = 0.0;
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    lift_step = steps[steps.size() / 2];
  }
  if (!(lift_step > 0.0)) lift_step = 1e-3;
  std::vector<double> w(down.size(), 0.0);
  for (std::size_t k = 1; k < down.size(); ++k) {
    const bool same_stroke = down[k] == down[k - 1] + 1;
    w[k] = w[k - 1] + (same_stroke ? samples[down[k]].t_s - samples[down[k - 1]].t_s : lift_step);
  }
  std::vector<double> at(options.length);
  for (std::size_t i = 0; i < options.length; ++i) {
    at[i] = w.back() * static_cast<double>(i) / static_cast<double>(options.length - 1);
  }
  at.back() = w.back();
  HATTR_THROW_UNLESS(w.back() > 0.0, "{}: no writing time (every pen-down sample at one time); expected a recording", where);

  // Each channel the profile has, resampled and normalized.
  const bool tilt = profile.rawChannels().tilt;
  FeatureSeries out;
  out.writing_time_s = w.back();
  std::vector<double> values(down.size());
  for (std::size_t c = 0; c < kFeatureChannels; ++c) {
    const auto channel = static_cast<FeatureChannel>(c);
    if ((channel == FeatureChannel::kAzimuth || channel == FeatureChannel::kAltitude) && !tilt) continue;
    for (std::size_t k = 0; k < down.size(); ++k) {
      const Sample& s = samples[down[k]];
      switch (channel) {
        case FeatureChannel::kX: values[k] = s.p_WT.x(); break;
        case FeatureChannel::kY: values[k] = s.p_WT.y(); break;
        case FeatureChannel::kForce: values[k] = s.f_user_W.norm(); break;
        case FeatureChannel::kAzimuth: values[k] = s.tilt_azimuth_rad; break;
        case FeatureChannel::kAltitude: values[k] = s.tilt_altitude_rad; break;
        case FeatureChannel::kVx: values[k] = s.v_WT.x(); break;
        case FeatureChannel::kVy: values[k] = s.v_WT.y(); break;
      }
    }
    try {
      out.channels[c] = analysis::normalize(analysis::interpolateAt(w, values, at), options.normalization);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: channel {}: {}", where, kChannelNames[c], e.what()));
    }
  }
  return out;
}

void requireChannels(const FeatureSeries& series, FeatureSet set, std::string_view where) {
  for (const FeatureChannel c : set.channels()) {
    HATTR_THROW_UNLESS(series.has(c),
                       "{}: the feature set {} needs the channel {}, which the profile does not have (a profile "
                       "without pen tilt has no angles); expected a profile with it, or another feature set",
                       where, set.name(), kChannelNames[static_cast<std::size_t>(c)]);
  }
}

namespace {

analysis::DtwOptions dtwOptions(const FeatureOptions& options, double abandon_raw) {
  analysis::DtwOptions o;
  o.cost = analysis::DtwCost::kAbsolute;
  o.band_fraction = options.band_fraction;
  o.abandon_above = abandon_raw;
  return o;
}

/// A bound widened by a relative 1e-9, so that rounding never abandons or skips a candidate that
/// ties the bound.
double slack(double bound) { return bound + 1e-9 * std::max(1.0, std::abs(bound)); }

}  // namespace

double timingDistance(const FeatureSeries& a, const FeatureSeries& b, FeatureSet set, const FeatureOptions& options) {
  if (!set.timing()) return 0.0;
  // The longer over the shorter: the same to the bit in either order.
  const double shorter = std::min(a.writing_time_s, b.writing_time_s);
  const double longer = std::max(a.writing_time_s, b.writing_time_s);
  return options.timing_weight * std::log(longer / shorter);
}

double featureDistance(const FeatureSeries& a, const FeatureSeries& b, FeatureSet set, const FeatureOptions& options,
                       double abandon_above) {
  const double length = static_cast<double>(options.length);
  const double timing = timingDistance(a, b, set, options);
  const double budget = std::isfinite(abandon_above) ? (slack(abandon_above) - timing) * length : abandon_above;
  double sum = 0.0;
  for (const FeatureChannel c : set.channels()) {
    if (budget - sum < 0.0) return std::numeric_limits<double>::infinity();
    const double d = analysis::dtwDistance(a[c], b[c], dtwOptions(options, budget - sum));
    if (!std::isfinite(d)) return std::numeric_limits<double>::infinity();
    sum += d;
  }
  return sum / length + timing;
}

// ---- Verification ----------------------------------------------------------------------------

std::string_view scoreRuleName(ScoreRule rule) { return rule == ScoreRule::kMean ? "mean" : "min"; }

ScoreRule parseScoreRule(std::string_view name) {
  if (name == "mean") return ScoreRule::kMean;
  if (name == "min") return ScoreRule::kMin;
  throw InputError(fmt::format("score rule: expected mean or min, got \"{}\"", name));
}

Enrolment enrol(std::string person, std::vector<FeatureSeries> references, FeatureSet set,
                const FeatureOptions& options) {
  HATTR_THROW_UNLESS(references.size() >= 2,
                     "person {}: {} reference profile; expected at least 2 (their spread normalises the scores)", person,
                     references.size());
  double sum = 0.0;
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < references.size(); ++i) {
    for (std::size_t j = i + 1; j < references.size(); ++j, ++pairs) {
      sum += featureDistance(references[i], references[j], set, options);
    }
  }
  const double spread = sum / static_cast<double>(pairs);
  HATTR_THROW_UNLESS(spread > 0.0, "person {}: the {} reference profiles are identical in {}; expected recordings that "
                                   "differ",
                     person, references.size(), set.name());
  return {std::move(person), std::move(references), spread};
}

double verificationScore(std::span<const double> d, double spread, ScoreRule rule) {
  HATTR_DEMAND(!d.empty() && spread > 0.0, "verification score: {} distances, spread {}", d.size(), spread);
  const double combined = rule == ScoreRule::kMin ? *std::min_element(d.begin(), d.end())
                                                  : std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(d.size());
  return combined / spread;
}

double verificationScore(const FeatureSeries& query, const Enrolment& e, FeatureSet set, const FeatureOptions& options,
                         ScoreRule rule) {
  std::vector<double> d;
  d.reserve(e.references.size());
  for (const auto& r : e.references) d.push_back(featureDistance(query, r, set, options));
  return verificationScore(d, e.spread, rule);
}

// ---- Identification ----------------------------------------------------------------------------

namespace {

/// The persons' best distances, ordered (distance, person), and each person's entry.
class PersonRanking {
 public:
  explicit PersonRanking(std::size_t top) : top_(top) {}
  /// The distance a new candidate must not exceed to matter: the top-th person's, or infinity.
  [[nodiscard]] double bound() const {
    if (order_.size() < top_) return std::numeric_limits<double>::infinity();
    return std::next(order_.begin(), static_cast<std::ptrdiff_t>(top_ - 1))->first;
  }
  /// The bound for a candidate of `person`: their own best counts too.
  [[nodiscard]] double boundFor(const std::string& person) const {
    const auto it = best_.find(person);
    return it == best_.end() ? bound() : std::min(bound(), it->second.distance);
  }
  void offer(const std::string& person, const std::string& key, double distance) {
    auto it = best_.find(person);
    if (it != best_.end()) {
      const RankedPerson& old = it->second;
      if (distance > old.distance || (distance == old.distance && key >= old.key)) return;
      order_.erase({old.distance, person});
    }
    best_[person] = {person, key, distance};
    order_.insert({distance, person});
  }
  [[nodiscard]] std::vector<RankedPerson> answer() const {
    std::vector<RankedPerson> out;
    for (const auto& [distance, person] : order_) {
      if (out.size() == top_) break;
      out.push_back(best_.at(person));
    }
    return out;
  }

 private:
  std::size_t top_;
  std::map<std::string, RankedPerson> best_;
  std::set<std::pair<double, std::string>> order_;
};


void checkSearch(const FeatureSeries& query, std::span<const Candidate> candidates, FeatureSet set, std::size_t top) {
  HATTR_THROW_UNLESS(top >= 1, "identify: top {}; expected at least 1", top);
  requireChannels(query, set, "the query");
  for (const Candidate& c : candidates) requireChannels(c.features, set, fmt::format("library entry {}", c.key));
}

}  // namespace

namespace {

/// The query's envelopes of the set's channels, within the band's radius, and their segment
/// envelope over kCoarseSegment steps, channel after channel as the index keeps the
/// candidates' means (analysis::lbSegmentMeans: below LB_Keogh).
struct QueryBounds {
  std::vector<analysis::DtwEnvelope> envelopes;
  analysis::DtwSegmentEnvelope coarse;
};

QueryBounds boundsOf(const FeatureSeries& query, FeatureSet set, const FeatureOptions& options) {
  const std::size_t radius = analysis::dtwBandRadius(options.length, options.length, options.band_fraction);
  QueryBounds b;
  for (const FeatureChannel c : set.channels()) {
    b.envelopes.push_back(analysis::dtwEnvelope(query[c], radius));
    b.coarse.append(analysis::dtwSegmentEnvelope(b.envelopes.back(), kCoarseSegment));
  }
  return b;
}

/// LB_Improved over the set's channels, abandoned above `limit` (then +infinity).
double improvedBound(const FeatureSeries& query, const QueryBounds& b, const SearchIndex& index, std::size_t i,
                     double timing, double limit) {
  const FeatureOptions& options = index.options();
  const double length = static_cast<double>(options.length);
  const std::size_t radius = analysis::dtwBandRadius(options.length, options.length, options.band_fraction);
  const double budget = (slack(limit) - timing) * length;
  // LB_Keogh of every channel first (cheap), then LB_Improved's second passes only if needed.
  double keogh = 0.0;
  std::array<double, kFeatureChannels> per_channel{};
  for (std::size_t k = 0; k < index.channels().size(); ++k) {
    per_channel[k] = analysis::lbKeogh(index.series(i, k), b.envelopes[k], analysis::DtwCost::kAbsolute, budget - keogh);
    keogh += per_channel[k];
    if (keogh > budget) return std::numeric_limits<double>::infinity();
  }
  double lb = keogh;
  for (std::size_t k = 0; k < index.channels().size(); ++k) {
    const double improved = analysis::lbImproved(index.series(i, k), query[index.channels()[k]], b.envelopes[k], radius,
                                                 analysis::DtwCost::kAbsolute, budget - (lb - per_channel[k]));
    lb += improved - per_channel[k];
    if (lb > budget) return std::numeric_limits<double>::infinity();
  }
  return lb / length + timing;
}

/// The distance of the query to candidate i, as featureDistance computes it, abandoned above `limit`.
double indexedDistance(const FeatureSeries& query, const SearchIndex& index, std::size_t i, double timing, double limit) {
  const FeatureOptions& options = index.options();
  const double length = static_cast<double>(options.length);
  const double budget = std::isfinite(limit) ? (slack(limit) - timing) * length : limit;
  double sum = 0.0;
  for (std::size_t k = 0; k < index.channels().size(); ++k) {
    if (budget - sum < 0.0) return std::numeric_limits<double>::infinity();
    const double d = analysis::dtwDistance(index.series(i, k), query[index.channels()[k]], dtwOptions(options, budget - sum));
    if (!std::isfinite(d)) return std::numeric_limits<double>::infinity();
    sum += d;
  }
  return sum / length + timing;
}

double indexedTiming(const FeatureSeries& query, const SearchIndex& index, std::size_t i) {
  if (!index.set().timing()) return 0.0;
  const double other = index.writingTime(i);
  const double shorter = std::min(query.writing_time_s, other), longer = std::max(query.writing_time_s, other);
  return index.options().timing_weight * std::log(longer / shorter);
}

}  // namespace

SearchIndex::SearchIndex(std::span<const Candidate> candidates, FeatureSet set, const FeatureOptions& options)
    : set_(set), options_(options), channels_(set.channels()) {
  checkFeatureOptions(options);
  coarse_stride_ = channels_.size() * ((options.length + kCoarseSegment - 1) / kCoarseSegment);
  series_.reserve(candidates.size() * channels_.size() * options.length);
  coarse_.reserve(candidates.size() * coarse_stride_);
  for (const Candidate& c : candidates) {
    requireChannels(c.features, set, fmt::format("library entry {}", c.key));
    for (const FeatureChannel ch : channels_) {
      const auto& v = c.features[ch];
      HATTR_THROW_UNLESS(v.size() == options.length,
                         "library entry {}: features of {} steps; expected {} (made with the same options)", c.key,
                         v.size(), options.length);
      series_.insert(series_.end(), v.begin(), v.end());
      // The segment means of the coarse bound, from the series themselves.
      analysis::appendSegmentMeans(v, kCoarseSegment, coarse_);
    }
    writing_time_s_.push_back(c.features.writing_time_s);
    persons_.push_back(c.person);
    keys_.push_back(c.key);
  }
}

std::size_t SearchIndex::bytes() const {
  std::size_t names = 0;
  for (std::size_t i = 0; i < persons_.size(); ++i) names += persons_[i].capacity() + keys_[i].capacity() + 2 * sizeof(std::string);
  return (series_.capacity() + coarse_.capacity() + writing_time_s_.capacity()) * sizeof(double) +
         names;
}

std::vector<RankedPerson> identify(const FeatureSeries& query, const SearchIndex& index, std::size_t top,
                                   SearchStats* stats) {
  HATTR_THROW_UNLESS(top >= 1, "identify: top {}; expected at least 1", top);
  requireChannels(query, index.set(), "the query");
  for (const FeatureChannel c : index.channels()) {
    HATTR_THROW_UNLESS(query[c].size() == index.options().length, "the query: features of {} steps; expected {}",
                       query[c].size(), index.options().length);
  }
  const QueryBounds qb = boundsOf(query, index.set(), index.options());
  const double length = static_cast<double>(index.options().length);

  // Every candidate's coarse bound, streaming the index's means through the vectorized kernel.
  thread_local std::vector<double> coarse;                          // reused: no page faults a query
  thread_local std::vector<std::pair<double, std::size_t>> bounds;
  coarse.resize(index.size());
  bounds.resize(index.size());
  analysis::lbSegmentMeans(index.allCoarse(), qb.coarse, coarse);
  for (std::size_t i = 0; i < index.size(); ++i) bounds[i] = {coarse[i] / length + indexedTiming(query, index, i), i};

  // Nearest coarse bounds first, ordered a chunk at a time (each chunk the next smallest,
  // twice the last): a search that ends early sorts little; stop where the bound passes the
  // answer's.
  std::size_t sorted_to = 0;
  std::size_t chunk = std::max<std::size_t>(256, 8 * top);
  const auto sortNextChunk = [&] {
    const auto first = bounds.begin() + static_cast<std::ptrdiff_t>(sorted_to);
    const std::size_t end = std::min(bounds.size(), sorted_to + chunk);
    const auto last = bounds.begin() + static_cast<std::ptrdiff_t>(end);
    if (last != bounds.end()) std::nth_element(first, last - 1, bounds.end());
    std::sort(first, last);
    sorted_to = end;
    chunk *= 2;
  };
  SearchStats s{.candidates = index.size()};
  PersonRanking ranking(top);
  for (std::size_t k = 0; k < bounds.size(); ++k) {
    if (k == sorted_to) sortNextChunk();
    const auto [lb, i] = bounds[k];
    if (lb > slack(ranking.bound())) break;
    const double limit = ranking.boundFor(index.person(i));
    const double timing = indexedTiming(query, index, i);
    ++s.lower_bounds;
    const bool ruled_out = std::isfinite(limit) && !std::isfinite(improvedBound(query, qb, index, i, timing, limit));
    if (ruled_out) {
      ++s.pruned_by_keogh;
      continue;
    }
    const double d = indexedDistance(query, index, i, timing, limit);
    if (!std::isfinite(d)) {
      ++s.dtw_abandoned;
      continue;
    }
    ++s.dtw_full;
    ranking.offer(index.person(i), index.key(i), d);
  }
  if (stats) *stats = s;
  return ranking.answer();
}

std::vector<RankedPerson> identify(const FeatureSeries& query, std::span<const Candidate> candidates, FeatureSet set,
                                   const FeatureOptions& options, std::size_t top, SearchStats* stats) {
  checkSearch(query, candidates, set, top);
  return identify(query, SearchIndex(candidates, set, options), top, stats);
}

std::vector<std::vector<RankedPerson>> identifyMany(std::span<const FeatureSeries> queries, const SearchIndex& index,
                                                    std::size_t top, unsigned threads, std::vector<SearchStats>* stats) {
  HATTR_THROW_UNLESS(threads >= 1, "identify: threads: expected at least 1, got 0");
  std::vector<std::vector<RankedPerson>> out(queries.size());
  if (stats) stats->assign(queries.size(), {});
  analysis::detail::forEachChunk(queries.size(), 1, threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t q = begin; q < end; ++q) {
      out[q] = identify(queries[q], index, top, stats ? &(*stats)[q] : nullptr);
    }
  });
  return out;
}

std::vector<RankedPerson> identifyBruteForce(const FeatureSeries& query, std::span<const Candidate> candidates,
                                             FeatureSet set, const FeatureOptions& options, std::size_t top) {
  checkSearch(query, candidates, set, top);
  PersonRanking ranking(top);
  for (const Candidate& c : candidates) ranking.offer(c.person, c.key, featureDistance(query, c.features, set, options));
  return ranking.answer();
}

}  // namespace hattr::library
