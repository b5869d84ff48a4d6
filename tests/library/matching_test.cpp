// Features, LB_Keogh, the exact nearest-person search against brute force, verification scores,
// error rates and DBA templates.

#include "hattr/library/matching.hpp"

#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/core/error.hpp"
#include "hattr/library/evaluation.hpp"
#include "hattr/library/profile_template.hpp"
#include "library/synthetic_writers.hpp"
#include "support/test_support.hpp"

namespace hattr::library {
namespace {

using ::testing::HasSubstr;

}  // namespace

void PrintTo(const RankedPerson& p, std::ostream* os) { *os << p.person << " " << p.key << " " << p.distance; }

namespace {

std::vector<double> randomWalk(std::mt19937_64& rng, std::size_t n) {
  std::normal_distribution<double> step(0.0, 1.0);
  std::vector<double> v(n);
  double x = 0.0;
  for (auto& y : v) y = x += step(rng);
  return v;
}

TEST(DtwLowerBound, TheEnvelopeIsTheWindowsMinAndMax) {
  // Lengths that leave every remainder of the blocks (2r + 1 values) for the last windows.
  std::mt19937_64 rng(3);
  for (const std::size_t n : {1u, 2u, 12u, 97u, 128u}) {
    for (const std::size_t r : {0u, 1u, 2u, 5u, 13u, 40u, 1000u}) {
      for (int repeat = 0; repeat < 4; ++repeat) {
        const auto s = randomWalk(rng, n);
        const auto e = analysis::dtwEnvelope(s, r);
        for (std::size_t i = 0; i < s.size(); ++i) {
          const std::size_t lo = i >= r ? i - r : 0, hi = std::min(s.size() - 1, i + r);
          EXPECT_EQ(e.lower[i], *std::min_element(s.begin() + lo, s.begin() + hi + 1)) << n << " " << r << " " << i;
          EXPECT_EQ(e.upper[i], *std::max_element(s.begin() + lo, s.begin() + hi + 1)) << n << " " << r << " " << i;
        }
      }
    }
  }
}

TEST(DtwLowerBound, LbKeoghAndLbImprovedNeverExceedTheBandedDtwAndAreTightForFarSeries) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t n = 20 + static_cast<std::size_t>(trial % 7) * 13;
    const auto a = randomWalk(rng, n);
    const auto b = randomWalk(rng, n);
    for (const double band : {0.05, 0.1, 0.3}) {
      for (const auto cost : {analysis::DtwCost::kAbsolute, analysis::DtwCost::kSquared}) {
        const std::size_t r = analysis::dtwBandRadius(n, n, band);
        analysis::DtwOptions o;
        o.band_fraction = band;
        o.cost = cost;
        const double d = analysis::dtwDistance(a, b, o);
        const double lb = analysis::lbKeogh(b, analysis::dtwEnvelope(a, r), cost);
        EXPECT_LE(lb, d * (1 + 1e-12) + 1e-12) << trial << " band " << band;
        // LB_Improved adds its second pass: between LB_Keogh and the distance.
        const double improved = analysis::lbImproved(b, a, analysis::dtwEnvelope(a, r), r, cost);
        EXPECT_GE(improved, lb) << trial << " band " << band;
        EXPECT_LE(improved, d * (1 + 1e-12) + 1e-12) << trial << " band " << band;
      }
    }
  }
  // A series far above the other: the bound is the whole distance (every point's nearest is the top).
  const std::vector<double> low(30, 0.0), high(30, 5.0);
  EXPECT_DOUBLE_EQ(analysis::lbKeogh(high, analysis::dtwEnvelope(low, 3), analysis::DtwCost::kAbsolute), 150.0);
  EXPECT_THAT(test::inputErrorOf([&] { (void)analysis::lbKeogh(high, analysis::dtwEnvelope(std::vector<double>(5, 0.0), 1),
                                                    analysis::DtwCost::kAbsolute); }),
              HasSubstr("expected the same length"));
}

TEST(DtwLowerBound, TheSegmentBoundNeverExceedsLbKeoghForManyCandidatesAtOnce) {
  // 40 candidates of two channels each, against a query's two envelopes, at once and one by one.
  std::mt19937_64 rng(11);
  for (const std::size_t n : {13u, 64u, 128u}) {
    for (const std::size_t segment : {1u, 4u, 8u, 32u}) {
      const std::size_t r = analysis::dtwBandRadius(n, n, 0.1);
      const auto qx = randomWalk(rng, n), qy = randomWalk(rng, n);
      const auto ex = analysis::dtwEnvelope(qx, r), ey = analysis::dtwEnvelope(qy, r);
      analysis::DtwSegmentEnvelope e = analysis::dtwSegmentEnvelope(ex, segment);
      e.append(analysis::dtwSegmentEnvelope(ey, segment));
      std::vector<double> means;
      std::vector<double> keogh;
      for (int c = 0; c < 40; ++c) {
        const auto cx = randomWalk(rng, n), cy = randomWalk(rng, n);
        analysis::appendSegmentMeans(cx, segment, means);
        analysis::appendSegmentMeans(cy, segment, means);
        keogh.push_back(analysis::lbKeogh(cx, ex, analysis::DtwCost::kAbsolute) +
                        analysis::lbKeogh(cy, ey, analysis::DtwCost::kAbsolute));
      }
      std::vector<double> bound(40);
      analysis::lbSegmentMeans(means, e, bound);
      for (int c = 0; c < 40; ++c) {
        EXPECT_GE(bound[c], 0.0);
        EXPECT_LE(bound[c], keogh[c] * (1 + 1e-12) + 1e-12) << n << " " << segment << " " << c;
      }
      // Segments of one value: the bound is LB_Keogh itself.
      if (segment == 1) {
        for (int c = 0; c < 40; ++c) EXPECT_NEAR(bound[c], keogh[c], 1e-9 * (1 + keogh[c]));
      }
    }
  }
  // A constant series far above the other: every segment's gap is the whole distance.
  const std::vector<double> low(30, 0.0), high(30, 5.0);
  std::vector<double> means;
  analysis::appendSegmentMeans(high, 8, means);
  double bound = 0.0;
  analysis::lbSegmentMeans(means, analysis::dtwSegmentEnvelope(analysis::dtwEnvelope(low, 3), 8), std::span(&bound, 1));
  EXPECT_DOUBLE_EQ(bound, 150.0);
  EXPECT_THAT(test::inputErrorOf([&] {
                std::vector<double> two(2);
                analysis::lbSegmentMeans(means, analysis::dtwSegmentEnvelope(analysis::dtwEnvelope(low, 3), 8), two);
              }),
              HasSubstr("4 means for 2 candidates; expected 4 a candidate"));
  EXPECT_THAT(test::inputErrorOf([&] { (void)analysis::dtwSegmentEnvelope(analysis::dtwEnvelope(low, 3), 0); }),
              HasSubstr("segment 0"));
}

TEST(LibraryFeatures, ALiftAddsOneStepOfWritingTimeAndEveryChannelIsNormalized) {
  const HapticProfile p = test::syntheticSignature(3, 0);
  const FeatureSeries f = extractFeatures(p, {}, "p");
  // Pen-down time: the samples' span less the gap between the strokes (the lift sample's 10 ms
  // and the 100 ms the writer waited, 120 ms from the last pen-down sample to the next) plus
  // one median step (10 ms).
  EXPECT_NEAR(f.writing_time_s, p.duration_s() - 0.12 + 0.01, 1e-9);
  for (std::size_t c = 0; c < kFeatureChannels; ++c) {
    ASSERT_EQ(f.channels[c].size(), 128u) << c;
    const auto [lo, hi] = std::minmax_element(f.channels[c].begin(), f.channels[c].end());
    EXPECT_NEAR(*hi - *lo, 1.0, 1e-9) << c;  // the paper's (x - mean) / range
  }
  // No tilt, no angles; the feature set that needs them says so.
  const FeatureSeries flat = extractFeatures(test::syntheticSignature(3, 0, 7, false), {}, "flat.csv");
  EXPECT_FALSE(flat.has(FeatureChannel::kAzimuth));
  EXPECT_THAT(test::inputErrorOf([&] { requireChannels(flat, parseFeatureSet("shape+angles"), "flat.csv"); }),
              HasSubstr("flat.csv: the feature set shape+angles needs the channel azimuth"));
  EXPECT_THAT(test::inputErrorOf([&] { (void)parseFeatureSet("shape+colour"); }), HasSubstr("unknown feature \"colour\""));
  EXPECT_EQ(parseFeatureSet("force+shape").name(), "shape+force");
  EXPECT_EQ(parseFeatureSet("all").name(), "all");
  EXPECT_THAT(test::inputErrorOf([&] { (void)extractFeatures(HapticProfile(), {}, "empty.csv"); }),
              HasSubstr("empty.csv: 0 pen-down samples"));
  EXPECT_THAT(test::inputErrorOf([&] { checkFeatureOptions({.length = 4}); }), HasSubstr("at least 8"));
}

TEST(LibraryFeatures, TheDistanceIsSymmetricAndAbandonsOnlyAboveItsBound) {
  const FeatureOptions o;
  const FeatureSet set = parseFeatureSet("all");
  const auto a = extractFeatures(test::syntheticSignature(1, 0), o, "a");
  const auto b = extractFeatures(test::syntheticSignature(2, 0), o, "b");
  const double d = featureDistance(a, b, set, o);
  EXPECT_GT(d, 0.0);
  EXPECT_EQ(featureDistance(b, a, set, o), d);
  EXPECT_EQ(featureDistance(a, b, set, o, d), d);  // at the bound: kept
  EXPECT_TRUE(std::isinf(featureDistance(a, b, set, o, 0.5 * d)));
  EXPECT_EQ(featureDistance(a, a, set, o), 0.0);
}

/// A gallery of synthetic writers, `takes` each.
std::vector<Candidate> gallery(int writers, int takes, const FeatureOptions& o, std::uint64_t seed) {
  std::vector<Candidate> out;
  for (int w = 0; w < writers; ++w) {
    for (int t = 0; t < takes; ++t) {
      out.push_back({"W" + std::to_string(w), fmt::format("W{}/{}", w, t),
                     extractFeatures(test::syntheticSignature(w, t, seed), o, "gallery")});
    }
  }
  return out;
}

TEST(LibraryIdentify, TheBoundedSearchReturnsBruteForcesRanksForEveryFeatureSet) {
  const FeatureOptions o;
  const auto candidates = gallery(40, 3, o, 11);
  std::size_t full = 0, total = 0;
  for (int q = 0; q < 12; ++q) {
    const auto query = extractFeatures(test::syntheticSignature(q * 3, 9, 12), o, "query");
    for (const auto& set : reportedFeatureSets()) {
      for (const std::size_t top : {1u, 5u}) {
        SearchStats stats;
        const auto fast = identify(query, candidates, set, o, top, &stats);
        const auto brute = identifyBruteForce(query, candidates, set, o, top);
        ASSERT_EQ(fast, brute) << "query " << q << " " << set.name() << " top " << top;
        full += stats.dtw_full;
        total += stats.candidates;
      }
    }
  }
  // The bounds prune: far fewer full distances than candidates.
  EXPECT_LT(full, total / 2);
  // A query of a known writer finds them first.
  const auto mine = identify(extractFeatures(test::syntheticSignature(7, 20, 11), o, "q"), candidates,
                             parseFeatureSet("shape+force"), o, 3);
  EXPECT_EQ(mine.front().person, "W7");
}

TEST(LibraryIdentify, TiesAreBrokenByPersonThenKeyInBothSearches) {
  // Two persons with the same profile: the same distance; the first name ranks first.
  const FeatureOptions o;
  const auto f = extractFeatures(test::syntheticSignature(1, 0), o, "f");
  const auto g = extractFeatures(test::syntheticSignature(2, 0), o, "g");
  const std::vector<Candidate> c{{"B", "b/1", f}, {"A", "a/2", f}, {"A", "a/1", f}, {"C", "c/1", g}};
  const auto fast = identify(g, c, parseFeatureSet("shape"), o, 3);
  EXPECT_EQ(fast, identifyBruteForce(g, c, parseFeatureSet("shape"), o, 3));
  ASSERT_EQ(fast.size(), 3u);
  EXPECT_EQ(fast[0].person, "C");
  EXPECT_EQ(fast[1].person, "A");
  EXPECT_EQ(fast[1].key, "a/1");
  EXPECT_EQ(fast[2].person, "B");
}

TEST(LibraryVerify, AScoreIsTheRulesDistanceOverTheEnrolmentSpread) {
  EXPECT_DOUBLE_EQ(verificationScore(std::vector<double>{1, 2, 3}, 2.0, ScoreRule::kMean), 1.0);
  EXPECT_DOUBLE_EQ(verificationScore(std::vector<double>{1, 2, 3}, 2.0, ScoreRule::kMin), 0.5);
  const FeatureOptions o;
  const FeatureSet set = parseFeatureSet("shape+force");
  std::vector<FeatureSeries> refs;
  for (int t = 0; t < 5; ++t) refs.push_back(extractFeatures(test::syntheticSignature(4, t), o, "r"));
  const Enrolment e = enrol("W4", refs, set, o);
  const double own = verificationScore(extractFeatures(test::syntheticSignature(4, 9), o, "own"), e, set, o, ScoreRule::kMean);
  const double other = verificationScore(extractFeatures(test::syntheticSignature(5, 9), o, "x"), e, set, o, ScoreRule::kMean);
  EXPECT_LT(own, other);
  EXPECT_THAT(test::inputErrorOf([&] { (void)enrol("W4", {refs[0]}, set, o); }), HasSubstr("1 reference profile; expected at least 2"));
  EXPECT_THAT(test::inputErrorOf([&] { (void)enrol("W4", {refs[0], refs[0]}, set, o); }), HasSubstr("identical"));
}

TEST(LibraryErrorRates, EerFarAndFrrByHand) {
  // Genuine 1..4, impostors 3..6: at 3, FRR 1/4 and FAR 1/4 (3 <= 3 accepted).
  const std::vector<double> genuine{1, 2, 3, 4}, impostor{3, 5, 6, 4.5};
  const ErrorRates r = equalErrorRate(genuine, impostor);
  EXPECT_DOUBLE_EQ(r.eer_threshold, 3.0);
  EXPECT_DOUBLE_EQ(r.eer, 0.25);
  const auto [far, frr] = errorRatesAt(genuine, impostor, 4.0);
  EXPECT_DOUBLE_EQ(far, 0.25);
  EXPECT_DOUBLE_EQ(frr, 0.0);
  // Apart: 0.
  EXPECT_DOUBLE_EQ(equalErrorRate({1, 2}, {3, 4}).eer, 0.0);
  const auto det = detCurve({1, 2}, {3, 4});
  ASSERT_EQ(det.size(), 4u);
  EXPECT_EQ(det.front(), std::make_pair(0.0, 0.5));
  EXPECT_EQ(det.back(), std::make_pair(1.0, 0.0));
  EXPECT_THAT(test::inputErrorOf([&] { (void)equalErrorRate({}, {1}); }), HasSubstr("0 genuine"));
}

TEST(LibraryTemplate, DbaOfShiftedCopiesIsTheCurveAndItsSpreadIsTheirs) {
  // Three takes of one writer: the template lies among them, nearer each than they are to each other on average.
  std::vector<HapticProfile> takes;
  for (int t = 0; t < 5; ++t) takes.push_back(test::syntheticSignature(6, t));
  const ProfileTemplate t = buildTemplate(takes, {.subject = "W6", .skill = "signature"});
  EXPECT_EQ(t.recordings, 5u);
  ASSERT_EQ(t.spread_m.size(), t.profile.size());
  EXPECT_GE(t.iterations, 1);
  const FeatureOptions o;
  const FeatureSet set = parseFeatureSet("shape+force");
  const auto tf = extractFeatures(t.profile, o, "template");
  double to_template = 0, between = 0;
  int pairs = 0;
  for (int a = 0; a < 5; ++a) {
    const auto fa = extractFeatures(takes[static_cast<std::size_t>(a)], o, "a");
    to_template += featureDistance(tf, fa, set, o) / 5.0;
    for (int b = a + 1; b < 5; ++b, ++pairs) between += featureDistance(fa, extractFeatures(takes[static_cast<std::size_t>(b)], o, "b"), set, o);
  }
  EXPECT_LT(to_template, between / pairs);
  // Its spread is about the takes' noise and amplitude jitter: under a millimetre.
  const double mean_spread = std::accumulate(t.spread_m.begin(), t.spread_m.end(), 0.0) / static_cast<double>(t.spread_m.size());
  EXPECT_GT(mean_spread, 0.0);
  EXPECT_LT(mean_spread, 1e-3);
  EXPECT_THAT(test::inputErrorOf([&] { (void)buildTemplate({takes[0]}, {.subject = "W6", .skill = "signature"}); }),
              HasSubstr("1 recording; expected at least 2"));
  EXPECT_THAT(test::inputErrorOf([&] { (void)libraryTemplate("library:lib.sqlite"); }), HasSubstr("expected library:PATH#PERSON/SKILL"));
}

}  // namespace
}  // namespace hattr::library
