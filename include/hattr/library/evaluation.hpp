#pragma once
/// Verification and identification measured with a stated protocol, on a library's labels.
///
/// The SVC2004 protocol (docs/library.md), over a set of writers: for each writer, `runs` runs,
/// each enrolling `enrolled` genuine profiles drawn at random (seeded) from the writer's first
/// session and testing the writer's second-session genuine profiles, every imitation of the
/// writer (skilled forgeries) and one genuine profile of each of `random_forgers` other writers
/// of the set (random forgeries). Scores are pooled over writers and runs under one global
/// threshold: a-posteriori EER on the set's own scores; FAR and FRR at an a-priori threshold
/// fixed on the development writers (their EER threshold), never on the scores it is applied
/// to. Closed-set identification: each second-session genuine profile against the first-session
/// genuine profiles of every writer of the set, rank 1 and rank 5 (persons ranked by their
/// nearest profile, ties by name).
///
/// Offline code, any thread but the servo thread; it runs DTWs on up to `threads` threads.

#include <cstdint>
#include <string>
#include <vector>

#include "hattr/library/matching.hpp"
#include "hattr/library/profile_library.hpp"

namespace hattr::library {

struct ProtocolOptions {
  FeatureOptions features;
  ScoreRule rule = ScoreRule::kMean;
  std::uint64_t seed = 2004;
  int runs = 10;
  int enrolled = 5;
  int random_forgers = 20;
  std::string skill = "signature";
  std::vector<FeatureSet> sets = reportedFeatureSets();
  std::vector<std::string> development;  ///< the writers choices are fixed on (SVC2004: U1–U20)
  std::vector<std::string> evaluation;   ///< the writers results are reported on (U21–U40)
  unsigned threads = 2;
};

/// The SVC2004 split of a library imported with `hattr library import svc2004`: development
/// U1–U20, evaluation U21–U40; InputError if the library does not hold those writers.
ProtocolOptions svc2004Protocol(const ProfileLibrary& library);

/// One verification score.
struct ScoreRow {
  std::string split;   ///< "development", "evaluation" or "all"
  std::string set;     ///< the feature set's name
  std::string person;  ///< the claimed writer
  int run = 0;
  std::string query;   ///< the tested entry's key
  std::string kind;    ///< "genuine", "skilled" or "random"
  double score = 0.0;  ///< lower is more like the claimed writer
};

/// Error rates of genuine scores against impostor scores (accepted when score <= threshold).
struct ErrorRates {
  double eer = 0.0;              ///< a-posteriori: where FAR and FRR meet on these scores
  double eer_threshold = 0.0;    ///< the threshold that gives it
  double prior_threshold = 0.0;  ///< a-priori: fixed on the development writers
  double far = 0.0;              ///< at prior_threshold
  double frr = 0.0;              ///< at prior_threshold
  std::size_t genuine = 0;
  std::size_t impostor = 0;
};

/// The a-posteriori EER of genuine against impostor scores: over every score as a threshold,
/// the one where |FAR − FRR| is least (the lowest such), EER = (FAR + FRR) / 2 there. Throws
/// InputError for an empty side.
ErrorRates equalErrorRate(std::vector<double> genuine, std::vector<double> impostor);
/// FAR and FRR at a threshold.
std::pair<double, double> errorRatesAt(const std::vector<double>& genuine, const std::vector<double>& impostor,
                                       double threshold);
/// The DET curve: (FAR, FRR) at every score as a threshold, FAR ascending.
std::vector<std::pair<double, double>> detCurve(std::vector<double> genuine, std::vector<double> impostor);

/// One feature set's results on one split of writers.
struct SplitResult {
  std::string split;
  std::size_t writers = 0;
  ErrorRates skilled;
  ErrorRates random;
  double rank1 = 0.0;  ///< closed-set identification accuracy at rank 1
  double rank5 = 0.0;
  std::size_t probes = 0;
  std::vector<std::pair<double, double>> det_skilled;
  std::vector<std::pair<double, double>> det_random;
};

struct SetResult {
  FeatureSet set;
  std::vector<SplitResult> splits;  ///< development, evaluation, all
};

/// What a week does to a writer: per feature set, the mean distance between two genuine
/// profiles of one writer within a session, across the two sessions, and between writers.
struct ClaimResult {
  std::string set;
  double within_session = 0.0;
  double across_sessions = 0.0;
  double between_writers = 0.0;
  /// The share of writers whose own first session is nearer their second session (mean distance)
  /// than any other writer's first session is.
  double writers_nearer_themselves = 0.0;
};

/// Whether a template is a better reference than one recording: for each evaluation writer,
/// the template of the first run's enrolled first-session profiles and each of those profiles
/// alone, against every second-session profile (held out), with the shape+force features.
struct TemplateResult {
  double template_distance = 0.0;  ///< mean distance of the templates to the held-out profiles
  double single_distance = 0.0;    ///< mean distance of the single recordings to them
  double writers_better = 0.0;     ///< share of writers whose template is nearer than their mean single
  std::size_t writers = 0;
};

/// The paper's Figure 3 on a real writer: one evaluation writer's force profiles (the feature
/// channel |f|, normalized, on writing time from 0 to 1) of both sessions, a week apart.
struct WeekExample {
  std::string person;
  std::vector<std::vector<double>> first, second;
};

struct EvaluationResult {
  ProtocolOptions options;
  std::string protocol = "svc2004";
  std::vector<SetResult> sets;
  std::vector<ClaimResult> claim;  ///< on the evaluation writers
  TemplateResult templates;        ///< on the evaluation writers
  WeekExample week;                ///< the first evaluation writer
  std::vector<ScoreRow> scores;
  double seconds = 0.0;
  std::size_t distances = 0;  ///< per-channel DTWs computed
};

/// Runs the protocol on the library's `options.skill` profiles.
EvaluationResult evaluate(const ProfileLibrary& library, const ProtocolOptions& options);

}  // namespace hattr::library
