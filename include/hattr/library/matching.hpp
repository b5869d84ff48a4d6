#pragma once
/// Comparing haptic profiles for identity: feature series, distances, verification against a
/// person's enrolled profiles, and exact nearest-person search.
///
/// Features (docs/library.md). A profile's pen-down samples, in order, on *writing time* (the
/// time in the air between strokes left out: one median step across each lift), resampled
/// linearly at `length` evenly spaced steps (the paper's time scaling, onto a common grid rather
/// than one expert's steps, so every profile of a library is comparable with every other), and
/// each channel normalized as the paper does ((x − mean) / range by default). Channels by
/// feature: shape x, y; force |f| (the pen's force on the paper, proportional to a tablet's
/// pressure); angles azimuth, altitude; velocity vx, vy.
///
/// Distance: the paper's per-axis DTW with the absolute cost, each channel on its own path,
/// summed over the feature set's channels, within a Sakoe–Chiba band, divided by `length`; plus,
/// with timing, timing_weight·|ln(T_a / T_b)| of the two writing times.
///
/// Offline code: any thread but the servo thread. Bad input (a profile without the channels a
/// feature set needs, too few pen-down samples) throws hattr::InputError naming the profile.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/analysis/preprocess.hpp"
#include "hattr/core/haptic_profile.hpp"

namespace hattr::library {

/// The feature channels, in the order FeatureSeries keeps them.
enum class FeatureChannel : std::uint8_t { kX, kY, kForce, kAzimuth, kAltitude, kVx, kVy };
inline constexpr std::size_t kFeatureChannels = 7;
inline constexpr std::size_t kCoarseSegment = 8;  ///< the search's first bound's segments

/// A set of features, as bits: shape (x, y), force, angles, velocity, timing (the writing time,
/// which resampling to a common length takes out of the others).
struct FeatureSet {
  static constexpr unsigned kShape = 1, kForce = 2, kAngles = 4, kVelocity = 8, kTiming = 16;
  unsigned bits = kShape;
  friend bool operator==(FeatureSet, FeatureSet) = default;
  /// The channels of the set, in FeatureChannel order (timing has none: it is one number).
  [[nodiscard]] std::vector<FeatureChannel> channels() const;
  [[nodiscard]] bool timing() const { return (bits & kTiming) != 0; }
  /// "shape", "force", "shape+force", ..., "all" for all five.
  [[nodiscard]] std::string name() const;
};
/// Parses "shape", "force", "angles", "velocity", "timing", joined with '+', or "all"; InputError
/// otherwise.
FeatureSet parseFeatureSet(std::string_view text);
/// The sets an evaluation reports: each of the five alone, shape+force, shape+timing,
/// shape+force+timing, and all.
std::vector<FeatureSet> reportedFeatureSets();

struct FeatureOptions {
  std::size_t length = 128;       ///< steps every profile is resampled at (>= 8)
  double band_fraction = 0.1;     ///< the DTW band as a fraction of `length` (also the LB radius)
  analysis::Normalization normalization = analysis::Normalization::kPaper;
  /// The timing feature's weight: its distance is weight·|ln(T_a / T_b)| for writing times T.
  double timing_weight = 0.05;
};
/// Throws InputError naming the option for a length below 8, a band outside (0, 1] or a timing
/// weight that is negative or not finite.
void checkFeatureOptions(const FeatureOptions& options);

/// A profile's feature series: one vector of `length` values per channel it has (empty for a
/// channel it lacks: no tilt, no angles).
struct FeatureSeries {
  std::array<std::vector<double>, kFeatureChannels> channels;
  double writing_time_s = 0.0;  ///< the pen-down time (lifts left out) [s]
  [[nodiscard]] bool has(FeatureChannel c) const { return !channels[static_cast<std::size_t>(c)].empty(); }
  [[nodiscard]] const std::vector<double>& operator[](FeatureChannel c) const {
    return channels[static_cast<std::size_t>(c)];
  }
};

/// The features of a profile (every channel it has). `where` names it in errors.
FeatureSeries extractFeatures(const HapticProfile& profile, const FeatureOptions& options, std::string_view where);
/// Throws InputError naming `where` and the missing channel if `series` lacks one of `set`'s.
void requireChannels(const FeatureSeries& series, FeatureSet set, std::string_view where);

/// The timing part of a distance (0 unless the set has timing).
double timingDistance(const FeatureSeries& a, const FeatureSeries& b, FeatureSet set, const FeatureOptions& options);
/// The distance between two profiles' features over a set (see above). Returns +infinity as
/// soon as it is sure to exceed `abandon_above`.
double featureDistance(const FeatureSeries& a, const FeatureSeries& b, FeatureSet set, const FeatureOptions& options,
                       double abandon_above = std::numeric_limits<double>::infinity());

// ---- Verification -------------------------------------------------------------------------

/// How a query's distances to a person's references become one score.
enum class ScoreRule { kMean, kMin };
std::string_view scoreRuleName(ScoreRule rule);  ///< "mean", "min"
ScoreRule parseScoreRule(std::string_view name);

/// A person's enrolment for a skill: their reference profiles' features, and their own spread
/// (the mean distance between two of their references), which normalises their scores, as the
/// signature literature does: a writer who varies much is allowed more.
struct Enrolment {
  std::string person;
  std::vector<FeatureSeries> references;
  double spread = 0.0;
};
/// Enrols references: at least 2 (a spread needs two), not all the same. Throws InputError
/// naming the person otherwise.
Enrolment enrol(std::string person, std::vector<FeatureSeries> references, FeatureSet set, const FeatureOptions& options);

/// The normalised score of a query against an enrolment: rule(distances to the references) /
/// spread. Lower is more like the person. From the distances, for callers that cache them.
double verificationScore(std::span<const double> distances_to_references, double spread, ScoreRule rule);
double verificationScore(const FeatureSeries& query, const Enrolment& enrolment, FeatureSet set,
                         const FeatureOptions& options, ScoreRule rule);

// ---- Identification -----------------------------------------------------------------------

/// One profile a search may return.
struct Candidate {
  std::string person;
  std::string key;
  FeatureSeries features;
};

/// A person in a ranking: their nearest profile and its distance.
struct RankedPerson {
  std::string person;
  std::string key;
  double distance = 0.0;
  friend bool operator==(const RankedPerson&, const RankedPerson&) = default;
};

/// What a search did: how many full DTWs it ran against how many candidates.
struct SearchStats {
  std::size_t candidates = 0;
  std::size_t lower_bounds = 0;    ///< candidates past the coarse bound (every candidate has one)
  std::size_t pruned_by_keogh = 0; ///< of those, ruled out by LB_Keogh or LB_Improved
  std::size_t dtw_full = 0;      ///< distances computed to the end
  std::size_t dtw_abandoned = 0; ///< distances stopped early
};

/// Candidates laid out for search over one feature set: each candidate's series of the set's
/// channels side by side in one array, and their segment means in another, so a search streams
/// memory instead of chasing each candidate's vectors. Memory: (length + length / 8) × channels ×
/// 8 bytes a candidate, plus the names.
class SearchIndex {
 public:
  /// Checks every candidate has the set's channels at `options.length`; throws InputError naming one that does not.
  SearchIndex(std::span<const Candidate> candidates, FeatureSet set, const FeatureOptions& options);
  [[nodiscard]] std::size_t size() const { return persons_.size(); }
  [[nodiscard]] FeatureSet set() const { return set_; }
  [[nodiscard]] const FeatureOptions& options() const { return options_; }
  /// Candidate i's series of the set's k-th channel.
  [[nodiscard]] std::span<const double> series(std::size_t i, std::size_t k) const {
    return {series_.data() + (i * channels_.size() + k) * options_.length, options_.length};
  }
  /// Candidate i's means over segments of kCoarseSegment steps, channel after channel.
  [[nodiscard]] std::span<const double> coarse(std::size_t i) const {
    return {coarse_.data() + i * coarse_stride_, coarse_stride_};
  }
  /// Every candidate's coarse means, one candidate after another.
  [[nodiscard]] std::span<const double> allCoarse() const { return coarse_; }
  [[nodiscard]] const std::string& person(std::size_t i) const { return persons_[i]; }
  [[nodiscard]] const std::string& key(std::size_t i) const { return keys_[i]; }
  [[nodiscard]] double writingTime(std::size_t i) const { return writing_time_s_[i]; }
  [[nodiscard]] const std::vector<FeatureChannel>& channels() const { return channels_; }
  [[nodiscard]] std::size_t bytes() const;

 private:
  FeatureSet set_;
  FeatureOptions options_;
  std::vector<FeatureChannel> channels_;
  std::size_t coarse_stride_ = 0;
  std::vector<double> series_, coarse_, writing_time_s_;
  std::vector<std::string> persons_, keys_;
};

/// The `top` persons nearest to the query (by their nearest candidate; ties by person then
/// key), exactly, by a cascade of lower bounds: first the coarse bound of every candidate in
/// one vectorized pass (analysis::lbSegmentMeans over segments of kCoarseSegment steps, below
/// LB_Keogh), taken in ascending order; then LB_Improved (LB_Keogh of every channel, then their
/// second passes, Lemire 2009), abandoned at the answer's bound; then the DTW, abandoned once it
/// cannot enter the answer. The search stops once the next coarse bound exceeds the `top`-th
/// person's distance. The same answer as identifyBruteForce.
std::vector<RankedPerson> identify(const FeatureSeries& query, const SearchIndex& index, std::size_t top,
                                   SearchStats* stats = nullptr);
/// The same over candidates (an index made for the one query).
std::vector<RankedPerson> identify(const FeatureSeries& query, std::span<const Candidate> candidates, FeatureSet set,
                                   const FeatureOptions& options, std::size_t top, SearchStats* stats = nullptr);
/// identify() for many queries, on `threads` threads (a query each at a time): the same answers.
std::vector<std::vector<RankedPerson>> identifyMany(std::span<const FeatureSeries> queries, const SearchIndex& index,
                                                    std::size_t top, unsigned threads = 1,
                                                    std::vector<SearchStats>* stats = nullptr);
/// Every distance computed in full, then ranked: the baseline of tests and benchmarks.
std::vector<RankedPerson> identifyBruteForce(const FeatureSeries& query, std::span<const Candidate> candidates,
                                             FeatureSet set, const FeatureOptions& options, std::size_t top);

}  // namespace hattr::library
