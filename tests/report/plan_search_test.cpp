// The plan's search (report/plan.hpp) over outcomes drawn from a known power curve: it finds
// the smallest design that reaches the target, brackets it, gives the same answer whatever
// order or extra outcomes it is fed, and refuses what it cannot use.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/report/plan.hpp"

namespace hattr::report {
namespace {

using ::testing::HasSubstr;

/// A known power curve: logistic in the number of subjects, 0.8 at `crossing`.
struct Curve {
  double crossing = 40.0;
  double slope = 0.12;
  double top = 0.999;
  [[nodiscard]] double power(int n) const {
    const double shift = std::log(0.8 / (top - 0.8));  // power(crossing) = 0.8
    return top / (1.0 + std::exp(-(slope * (n - crossing) + shift)));
  }
};

/// Replicate r's uniform draw, shared by every design (common random numbers, as the studies').
double uniformOf(int replicate) {
  std::uint64_t x = static_cast<std::uint64_t>(replicate) * 0x9E3779B97F4A7C15ULL + 12345;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return static_cast<double>((x ^ (x >> 31)) >> 11) * 0x1.0p-53;
}

/// Runs a search to its end, answering each request from the curve.
template <typename PowerCurve>
PlanSearchResult searchOver(const PowerCurve& curve, const PlanSearchOptions& options, int* requests = nullptr) {
  PlanSearch search(options);
  while (const auto request = search.next()) {
    if (requests) ++*requests;
    for (int r = request->first; r < request->first + request->count; ++r) {
      search.record(request->subjects, r, uniformOf(r) < curve.power(request->subjects));
    }
  }
  return search.result();
}

/// A curve flat at the target from 30 to 150 subjects: no design there can be decided.
struct Plateau {
  [[nodiscard]] double power(int n) const { return n < 30 ? 0.2 : n <= 150 ? 0.8 : 0.999; }
};

/// The smallest n of the grid whose true power reaches 0.8.
int trueAnswer(const Curve& curve, const PlanSearchOptions& o) {
  for (int n = o.min_subjects; n <= o.max_subjects; n += o.step) {
    if (curve.power(n) >= o.target) return n;
  }
  return -1;
}

TEST(PlanSearch, FindsTheSmallestDesignThatReachesTheTargetWithinItsStatedRange) {
  const PlanSearchOptions options{.min_subjects = 3, .max_subjects = 200, .batch = 50, .max_replicates = 4000};
  for (const double crossing : {12.0, 40.0, 87.5, 150.0}) {
    const Curve curve{.crossing = crossing};
    const PlanSearchResult result = searchOver(curve, options);
    ASSERT_TRUE(result.answer) << crossing;
    const int truth = trueAnswer(curve, options);
    EXPECT_LE(result.range_low, truth) << crossing;
    EXPECT_GE(result.range_high, truth) << crossing;
    EXPECT_LE(result.range_low, *result.answer);
    EXPECT_GE(result.range_high, *result.answer);
    // Not vacuous: the bracket is a few designs wide on a curve this steep.
    EXPECT_LE(result.range_high - result.range_low, 8) << crossing;
    // The bracket's ends are decided: below the target under it, above it at its top.
    const auto below = std::find_if(result.points.begin(), result.points.end(),
                                    [&](const PlanPoint& p) { return p.subjects == result.range_low - 1; });
    if (below != result.points.end()) {
      EXPECT_EQ(below->decision, PlanDecision::kBelow);
    }
    EXPECT_EQ(result.point(result.range_high).decision, PlanDecision::kAbove);
    // Each point's power is its replicates' fraction, and the replicates add up.
    int replicates = 0;
    for (const auto& p : result.points) {
      replicates += p.power.trials;
      EXPECT_EQ(p.power.trials % options.batch, 0);
      EXPECT_NEAR(p.power.estimate, static_cast<double>(p.power.successes) / p.power.trials, 1e-15);
    }
    EXPECT_EQ(result.replicates, replicates);
  }
}

TEST(PlanSearch, WalksPastAFewUndecidedDesignsOnlyAndItsRangeStillHoldsTheAnswer) {
  const PlanSearchOptions options{.min_subjects = 3, .max_subjects = 200, .batch = 20, .max_replicates = 200};
  const PlanSearchResult result = searchOver(Plateau{}, options);
  ASSERT_TRUE(result.answer);
  const auto undecided = std::count_if(result.points.begin(), result.points.end(),
                                       [](const PlanPoint& p) { return p.decision == PlanDecision::kUndecided; });
  // The bisection's designs on the plateau (at most 8 on this grid) and at most 4 each side of
  // the answer (kMostUndecidedWalked): not the plateau's 121 designs.
  EXPECT_EQ(kMostUndecidedWalked, 4);
  EXPECT_GE(undecided, 1);
  EXPECT_LE(undecided, 16);
  // Every design from 30 on reaches the target (0.8 >= 0.8): the range holds the first, 30.
  EXPECT_LE(result.range_low, 30);
  EXPECT_GE(result.range_high, *result.answer);
  EXPECT_LE(result.range_low, *result.answer);
}

TEST(PlanSearch, SpendsFewReplicatesOnDesignsFarFromTheTarget) {
  const PlanSearchOptions options{.min_subjects = 3, .max_subjects = 200, .batch = 10, .max_replicates = 400};
  const PlanSearchResult result = searchOver(Curve{.crossing = 60.0, .slope = 0.2}, options);
  // Power near 0 is decided below at the first look (0 of 10: at most 52 % at the look's
  // 99.875 %); power near 1 above once 34 of 34 can exclude 80 % (0.000625^(1/34) > 0.8).
  EXPECT_EQ(result.point(3).power.trials, 10);
  EXPECT_EQ(result.point(200).power.trials, 40);
  EXPECT_EQ(result.point(3).decision, PlanDecision::kBelow);
  EXPECT_EQ(result.point(200).decision, PlanDecision::kAbove);
}

TEST(PlanSearch, SaysSoWhenTheLargestDesignFallsShort) {
  const PlanSearchOptions options{.max_subjects = 200, .batch = 20, .max_replicates = 400};
  const Curve weak{.crossing = 400.0, .slope = 0.01};  // 0.8 only at 400 subjects
  int requests = 0;
  const PlanSearchResult result = searchOver(weak, options, &requests);
  EXPECT_FALSE(result.answer);
  ASSERT_EQ(result.points.size(), 1u);  // the largest alone: no design can then reach it
  EXPECT_EQ(result.points[0].subjects, 200);
  EXPECT_EQ(result.points[0].decision, PlanDecision::kBelow);
  PlanSearchReport report{.label = "weak", .max_subjects = 200, .result = result};
  report.lab_s_per_subject = 3600.0;
  const std::string sentence = planSearchSentence(report, 0.8);
  EXPECT_THAT(sentence, HasSubstr("no design within 200 subjects reaches 80 % power: best "));
  EXPECT_THAT(sentence, HasSubstr(" at 200"));
}

TEST(PlanSearch, TheSmallestDesignIsTheAnswerWhenItSuffices) {
  const PlanSearchOptions options{.min_subjects = 20, .max_subjects = 60, .batch = 20, .max_replicates = 400};
  const PlanSearchResult result = searchOver(Curve{.crossing = 5.0, .slope = 0.5}, options);
  ASSERT_TRUE(result.answer);
  EXPECT_EQ(*result.answer, 20);
  EXPECT_EQ(result.range_low, 20);
}

TEST(PlanSearch, TheSameOutcomesInAnyOrderAndWithExtrasGiveTheSameAnswer) {
  // What a resume, MPI ranks or shards do: outcomes arrive in another order, some of them not
  // asked for (a shard ran its share of a batch the others had already decided).
  const PlanSearchOptions options{.min_subjects = 4, .max_subjects = 120, .step = 2, .batch = 25,
                                  .max_replicates = 1000};
  const Curve curve{.crossing = 50.0, .slope = 0.08};
  const PlanSearchResult direct = searchOver(curve, options);
  PlanSearch shuffled(options);
  std::mt19937 rng(7);
  while (const auto request = shuffled.next()) {
    std::vector<int> replicates;
    for (int r = request->first; r < request->first + request->count; ++r) replicates.push_back(r);
    std::shuffle(replicates.begin(), replicates.end(), rng);
    for (const int r : replicates) shuffled.record(request->subjects, r, uniformOf(r) < curve.power(request->subjects));
    // Another design's outcome, the curve's own: known early, it changes nothing.
    const int extra = static_cast<int>(rng() % 1000);
    shuffled.record(options.min_subjects + 2, extra, uniformOf(extra) < curve.power(options.min_subjects + 2));
  }
  const PlanSearchResult again = shuffled.result();
  ASSERT_EQ(again.answer, direct.answer);
  EXPECT_EQ(again.range_low, direct.range_low);
  EXPECT_EQ(again.range_high, direct.range_high);
  ASSERT_EQ(again.points.size(), direct.points.size());
  for (std::size_t i = 0; i < direct.points.size(); ++i) {
    EXPECT_EQ(again.points[i].subjects, direct.points[i].subjects);
    EXPECT_EQ(again.points[i].power.successes, direct.points[i].power.successes);
    EXPECT_EQ(again.points[i].power.trials, direct.points[i].power.trials);
  }
}

TEST(PlanSearch, RefusesBadOptionsOutcomesOffTheGridAndContradictions) {
  const auto refused = [](PlanSearchOptions o, const char* what) {
    try {
      PlanSearch search(o);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  refused({.target = 1.0}, "--power: expected a target power in (0, 1), got 1");
  refused({.target = 0.0}, "--power: expected a target power in (0, 1), got 0");
  refused({.confidence = 1.5}, "--confidence");
  refused({.min_subjects = 50, .max_subjects = 40}, "--max-subjects: expected at least --min-subjects (50), got 40");
  refused({.batch = 30, .max_replicates = 100}, "--max-replicates: expected a whole number of batches of 30");
  refused({.step = 0}, "--step");

  PlanSearch search({.min_subjects = 4, .max_subjects = 20, .step = 4, .batch = 10, .max_replicates = 100});
  EXPECT_THROW(search.record(6, 0, true), InputError);    // off the grid 4, 8, ...
  EXPECT_THROW(search.record(24, 0, true), InputError);   // past the largest
  EXPECT_THROW(search.record(8, 100, true), InputError);  // past max_replicates
  search.record(8, 3, true);
  search.record(8, 3, true);  // the same again is fine
  EXPECT_THROW(search.record(8, 3, false), InputError);
  EXPECT_THROW((void)search.result(), std::logic_error);  // not ended
}

}  // namespace
}  // namespace hattr::report
