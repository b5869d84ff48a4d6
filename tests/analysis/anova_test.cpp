// Two-way ANOVA, Tukey HSD, the studentized range distribution and descriptive statistics
// against reference values from R 4.2.2. Every literal below was printed by
//   Rscript tests/analysis/anova_reference.R
// (the script beside this file; it lists the exact R commands: aov(), summary(),
// TukeyHSD(), ptukey(), qtukey(), pf(), var()). The data sets are R's warpbreaks, npk and
// sleep, typed in below, and two seeded random balanced designs generated in that script
// (set.seed(20261121) and set.seed(7)) whose values are typed in too. The tests do not
// need R. Agreement is required to 1e-8 relative unless a comment says why not.

#include "hattr/analysis/anova.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/analysis/studentized_range.hpp"
#include "hattr/core/error.hpp"
#include "support/test_support.hpp"

namespace hattr::analysis {
namespace {

using ::testing::HasSubstr;

using test::kNaN;
using test::kInf;
constexpr double kAnovaRelTol = 1e-8;

// |actual - expected| <= tol * |expected| (NaN matches NaN).
void expectRel(double actual, double expected, const std::string& what, double tol = kAnovaRelTol) {
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(actual)) << what << ": expected NaN, got " << actual;
    return;
  }
  EXPECT_NEAR(actual, expected, tol * std::abs(expected)) << what;
}

// One row of R's summary(aov()) plus partial eta squared (NaN = R's NA).
struct RowRef {
  const char* source;
  std::size_t df;
  double sum_sq, mean_sq, f, p, partial_eta_sq;
};

void expectTable(const AnovaTable& table, std::span<const RowRef> expected) {
  ASSERT_EQ(table.rows.size(), expected.size());
  for (std::size_t r = 0; r < expected.size(); ++r) {
    const AnovaRow& row = table.rows[r];
    const RowRef& e = expected[r];
    EXPECT_EQ(row.source, e.source);
    EXPECT_EQ(row.df, e.df) << e.source;
    expectRel(row.sum_sq, e.sum_sq, fmt::format("{} SS", e.source));
    expectRel(row.mean_sq, e.mean_sq, fmt::format("{} MS", e.source));
    expectRel(row.f, e.f, fmt::format("{} F", e.source));
    expectRel(row.p, e.p, fmt::format("{} p", e.source));
    expectRel(row.partial_eta_sq, e.partial_eta_sq, fmt::format("{} partial eta²", e.source));
  }
}

// One row of R's TukeyHSD(): diff, lwr, upr, p adj, then lwr and upr recomputed in R with
// an accurate quantile (R's qtukey() stops its secant iteration at |Δq| < 1e-4 and is off
// by up to ~1e-7 relative; see anova_reference.R).
struct TukeyRef {
  const char* comparison;
  double diff, r_lower, r_upper, p_adjusted, lower, upper;
};

void expectTukey(const TukeyResult& result, std::span<const TukeyRef> expected) {
  ASSERT_EQ(result.comparisons.size(), expected.size());
  for (std::size_t r = 0; r < expected.size(); ++r) {
    const TukeyComparison& c = result.comparisons[r];
    const TukeyRef& e = expected[r];
    EXPECT_EQ(c.comparison, e.comparison);
    expectRel(c.diff, e.diff, fmt::format("{} diff", e.comparison));
    expectRel(c.lower, e.lower, fmt::format("{} lwr", e.comparison));
    expectRel(c.upper, e.upper, fmt::format("{} upr", e.comparison));
    expectRel(c.p_adjusted, e.p_adjusted, fmt::format("{} p adj", e.comparison));
    // R's own bounds, to the accuracy of R's qtukey().
    expectRel(c.lower, e.r_lower, fmt::format("{} lwr (R qtukey)", e.comparison), 3e-7);
    expectRel(c.upper, e.r_upper, fmt::format("{} upr (R qtukey)", e.comparison), 3e-7);
  }
}

// A factor column of `levels`, each repeated `each` times, the whole repeated `times`:
// R's rep(levels, each = each, times = times).
std::vector<std::string> rep(const std::vector<std::string>& levels, std::size_t each,
                             std::size_t times) {
  std::vector<std::string> column;
  for (std::size_t t = 0; t < times; ++t) {
    for (const auto& level : levels) column.insert(column.end(), each, level);
  }
  return column;
}

// ---- Data sets ------------------------------------------------------------------------------

// R: warpbreaks (breaks ~ wool * tension), 2 x 3 cells, 9 replicates.
TwoWayData warpbreaks() {
  TwoWayData d;
  d.a_name = "wool";
  d.b_name = "tension";
  d.y = {26, 30, 54, 25, 70, 52, 51, 26, 67, 18, 21, 29, 17, 12, 18, 35, 30, 36,
         36, 21, 24, 18, 10, 43, 28, 15, 26, 27, 14, 29, 19, 29, 31, 41, 20, 44,
         42, 26, 19, 16, 39, 28, 21, 39, 29, 20, 21, 24, 17, 13, 15, 15, 16, 28};
  d.a = rep({"A", "B"}, 27, 1);
  d.b = rep({"L", "M", "H"}, 9, 2);
  return d;
}

// R: npk (yield ~ N * block), 2 x 6 cells, 2 replicates; rows in npk's order.
TwoWayData npk() {
  TwoWayData d;
  d.a_name = "N";
  d.b_name = "block";
  d.y = {49.5, 62.8, 46.8, 57.0, 59.8, 58.5, 55.5, 56.0, 62.8, 55.8, 69.5, 55.0,
         62.0, 48.8, 45.5, 44.2, 52.0, 51.5, 49.8, 48.8, 57.2, 59.0, 53.2, 56.0};
  d.a = {"0", "1", "0", "1", "1", "1", "0", "0", "0", "1", "1", "0",
         "1", "1", "0", "0", "1", "0", "1", "0", "1", "1", "0", "0"};
  d.b = rep({"1", "2", "3", "4", "5", "6"}, 4, 1);
  return d;
}

// R: sleep (extra ~ group + ID), 2 x 10 cells, no replicates.
TwoWayData sleep() {
  TwoWayData d;
  d.a_name = "group";
  d.b_name = "ID";
  d.y = {0.7, -1.6, -0.2, -1.2, -0.1, 3.4, 3.7, 0.8, 0.0, 2.0,
         1.9, 0.8,  1.1,  0.1,  -0.1, 4.4, 5.5, 1.6, 4.6, 3.4};
  d.a = rep({"1", "2"}, 10, 1);
  d.b = rep({"1", "2", "3", "4", "5", "6", "7", "8", "9", "10"}, 1, 2);
  return d;
}

// R: set.seed(20261121); d1 <- expand.grid(subject = paste0("S", 1:6),
//   mode = c("BASIC", "PCONTROL", "ALPHA", "NONE"));
// d1$y <- round(rnorm(24, mean = 10, sd = 2) + rep(c(0, 1, 2, 0.5), each = 6), 3)
TwoWayData random1() {
  TwoWayData d;
  d.a_name = "mode";
  d.b_name = "subject";
  d.y = {10.917, 14.21,  10.786, 7.29,   11.642, 9.472,  13.044, 13.091,
         10.789, 13.119, 8.476,  11.723, 12.814, 10.878, 13.985, 13.865,
         14.571, 12.136, 14.71,  9.337,  10.245, 11.345, 13.615, 11.184};
  d.a = rep({"BASIC", "PCONTROL", "ALPHA", "NONE"}, 6, 1);
  d.b = rep({"S1", "S2", "S3", "S4", "S5", "S6"}, 1, 4);
  return d;
}

// R: set.seed(7); d2 <- expand.grid(rep = 1:3, subject = paste0("S", 1:4),
//   mode = c("BASIC", "PCONTROL", "ALPHA"));
// d2$y <- round(5 + rep(c(0, 0.8, 1.5), each = 12) + rep(rnorm(4, 0, 0.7), each = 3,
//   times = 3) + rnorm(36, 0, 1), 3)
TwoWayData random2() {
  TwoWayData d;
  d.a_name = "mode";
  d.b_name = "subject";
  d.y = {5.63,  5.654, 7.349, 4.045, 4.315, 6.352, 4.871, 7.231, 6.795, 5.035, 6.607, 5.179,
         6.507, 7.094, 7.396, 5.95,  5.802, 5.668, 6.62,  3.926, 6.587, 5.696, 6.264, 6.103,
         7.118, 7.825, 7.23,  6.381, 5.773, 5.584, 5.594, 5.452, 7.012, 5.106, 6.069, 6.526};
  d.a = rep({"BASIC", "PCONTROL", "ALPHA"}, 12, 1);
  d.b = rep({"S1", "S2", "S3", "S4"}, 3, 3);
  return d;
}

// ---- ANOVA tables -----------------------------------------------------------------------------

// R: summary(aov(breaks ~ wool * tension, data = warpbreaks))
TEST(TwoWayAnova, MatchesRsAovOnWarpbreaks) {
  // clang-format off
  const RowRef expected[] = {
    {"wool", 1, 450.66666666666691, 450.66666666666691, 3.7652883611186332, 0.058212975959559793, 0.072737706681969813},
    {"tension", 2, 2034.259259259258, 1017.129629629629, 8.4980466483580166, 0.00069262093671344511, 0.26149407502273325},
    {"wool:tension", 2, 1002.7777777777762, 501.38888888888812, 4.1890689668510346, 0.021044190727863191, 0.14860614842502157},
    {"Residuals", 48, 5745.1111111111131, 119.68981481481485, kNaN, kNaN, kNaN},
  };
  // clang-format on
  const AnovaTable table = twoWayAnova(warpbreaks());
  expectTable(table, expected);
  EXPECT_EQ(table.replicates, 9u);
  EXPECT_EQ(table.b_levels, (std::vector<std::string>{"L", "M", "H"}));
  EXPECT_EQ(table.row("wool:tension").error_term, "Residuals");
}

// R: summary(aov(yield ~ N * block, data = npk))
TEST(TwoWayAnova, MatchesRsAovOnNpk) {
  // clang-format off
  const RowRef expected[] = {
    {"N", 1, 189.28166666666661, 189.28166666666661, 9.2607330696783059, 0.010214000339807173, 0.43557919848426135},
    {"block", 5, 343.29499999999996, 68.658999999999992, 3.3591878338157923, 0.039671284512846398, 0.58327457460093601},
    {"N:block", 5, 98.518333333333231, 19.703666666666646, 0.96401516695886003, 0.47690161106922069, 0.28656683133517197},
    {"Residuals", 12, 245.27000000000015, 20.439166666666679, kNaN, kNaN, kNaN},
  };
  // clang-format on
  expectTable(twoWayAnova(npk()), expected);
}

// R: summary(aov(extra ~ group + ID, data = sleep)): no replicates, additive model.
TEST(TwoWayAnova, FitsTheAdditiveModelWithoutReplicatesLikeR) {
  // clang-format off
  const RowRef expected[] = {
    {"group", 1, 12.481999999999994, 12.481999999999994, 16.500881316098699, 0.0028328901973842776, 0.64707102125453597},
    {"ID", 9, 58.07800000000001, 6.4531111111111121, 8.53084606345476, 0.0019014038291320281, 0.89507752057454615},
    {"Residuals", 9, 6.8079999999999998, 0.75644444444444447, kNaN, kNaN, kNaN},
  };
  // clang-format on
  const AnovaTable table = twoWayAnova(sleep());
  expectTable(table, expected);
  EXPECT_EQ(table.replicates, 1u);
}

// R: summary(aov(y ~ mode + subject, data = d1)) on the seeded random design.
TEST(TwoWayAnova, MatchesRsAovOnARandomDesignWithoutReplicates) {
  // clang-format off
  const RowRef expected[] = {
    {"mode", 3, 16.326710999999992, 5.4422369999999978, 1.2403955958772337, 0.32997223226189493, 0.19876874419575433},
    {"subject", 5, 7.8335963333333609, 1.5667192666666723, 0.35708692553252463, 0.86974490612942845, 0.10636809038713856},
    {"Residuals", 15, 65.812515999999988, 4.3875010666666663, kNaN, kNaN, kNaN},
  };
  // clang-format on
  expectTable(twoWayAnova(random1()), expected);
  // Without replicates a random B changes nothing: every term is tested on the residual.
  expectTable(twoWayAnova(random1(), {.b_random = true}), expected);
}

// R: summary(aov(y ~ mode * subject, data = d2)) on the seeded random design.
TEST(TwoWayAnova, MatchesRsAovOnARandomDesignWithReplicates) {
  // clang-format off
  const RowRef expected[] = {
    {"mode", 2, 1.9051721666666717, 0.95258608333333583, 1.2450050547211804, 0.30587882419518281, 0.093998080754027241},
    {"subject", 3, 8.7308609999999849, 2.910286999999995, 3.8036688642462924, 0.02311801268490029, 0.32224462647946117},
    {"mode:subject", 6, 2.8963151666666738, 0.48271919444444561, 0.63090134068646597, 0.70415384982363927, 0.1362372666295982},
    {"Residuals", 24, 18.363030666666678, 0.7651262777777782, kNaN, kNaN, kNaN},
  };
  // clang-format on
  expectTable(twoWayAnova(random2()), expected);
}

// R: s <- summary(aov(y ~ mode * subject, data = d2))[[1]];
// F <- s[["Mean Sq"]][1] / s[["Mean Sq"]][3]; pf(F, s$Df[1], s$Df[3], lower.tail = FALSE);
// s[["Sum Sq"]][1] / (s[["Sum Sq"]][1] + s[["Sum Sq"]][3])
TEST(TwoWayAnova, TestsAAgainstTheInteractionWhenBIsRandom) {
  const double expected_f_p_eta[] = {1.9733751926513987, 0.2194876521544675, 0.3967879189101266};
  const AnovaTable fixed = twoWayAnova(random2());
  const AnovaTable mixed = twoWayAnova(random2(), {.b_random = true});
  const AnovaRow& mode = mixed.row("mode");
  EXPECT_EQ(mode.error_term, "mode:subject");
  expectRel(mode.f, expected_f_p_eta[0], "F");
  expectRel(mode.p, expected_f_p_eta[1], "p");
  expectRel(mode.partial_eta_sq, expected_f_p_eta[2], "partial eta²");
  // B and A:B stay tested against the residual (restricted mixed model).
  for (const char* source : {"subject", "mode:subject", "Residuals"}) {
    expectRel(mixed.row(source).f, fixed.row(source).f, source);
    expectRel(mixed.row(source).p, fixed.row(source).p, source);
  }
}

// Partitioning: the sums of squares add up to the total sum of squares.
TEST(TwoWayAnova, SumsOfSquaresAddUpToTheTotal) {
  for (const TwoWayData& data : {warpbreaks(), npk(), sleep(), random1(), random2()}) {
    double mean = 0.0;
    for (const double y : data.y) mean += y;
    mean /= static_cast<double>(data.y.size());
    double total = 0.0;
    for (const double y : data.y) total += (y - mean) * (y - mean);
    double sum = 0.0;
    std::size_t df = 0;
    for (const AnovaRow& row : twoWayAnova(data).rows) {
      sum += row.sum_sq;
      df += row.df;
    }
    expectRel(sum, total, data.a_name);
    EXPECT_EQ(df, data.y.size() - 1) << data.a_name;
  }
}

// ---- Refusals --------------------------------------------------------------------------------

TEST(TwoWayAnova, RefusesAMissingCellNamingIt) {
  TwoWayData d = warpbreaks();
  // Drop every observation of cell wool=B, tension=H (the last 9 rows).
  d.y.resize(45);
  d.a.resize(45);
  d.b.resize(45);
  EXPECT_EQ(test::inputErrorOf([&] { (void)twoWayAnova(d); }),
            "twoWayAnova: unbalanced design: expected 9 observations in each of the 2 x 3 cells "
            "wool x tension, got wool=B, tension=H: 0 (missing)");
}

TEST(TwoWayAnova, RefusesDifferingReplicateCountsNamingTheCells) {
  TwoWayData d = warpbreaks();
  d.b[8] = std::string("M");  // (not = "M": a GCC 12 -Wrestrict false positive, its bug 105329) one more in wool=A, tension=M, one fewer in wool=A, tension=L
  EXPECT_EQ(
      test::inputErrorOf([&] { (void)tukeyHsd(d, Factor::kA); }),
      "tukeyHsd: unbalanced design: expected 9 observations in each of the 2 x 3 cells "
      "wool x tension, got wool=A, tension=L: 8 (1 too few); wool=A, tension=M: 10 (1 extra)");
}

TEST(TwoWayAnova, RefusesBadColumnsSayingWhereAndWhat) {
  TwoWayData d = sleep();
  d.y.pop_back();
  EXPECT_EQ(test::inputErrorOf([&] { (void)twoWayAnova(d); }),
            "twoWayAnova: columns differ in length: expected equal lengths, got 20 (group), 20 "
            "(ID) and 19 (response)");
  d = sleep();
  d.y[3] = kNaN;
  EXPECT_EQ(test::inputErrorOf([&] { (void)twoWayAnova(d); }),
            "twoWayAnova: row 3: response: expected a finite number, got nan");
  d = sleep();
  d.a.assign(20, "1");
  EXPECT_EQ(test::inputErrorOf([&] { (void)twoWayAnova(d); }),
            "twoWayAnova: expected at least 2 levels of each factor, got 1 of group and 10 of ID");
  d = sleep();
  d.b_name = "group";
  EXPECT_THAT(test::inputErrorOf([&] { (void)twoWayAnova(d); }),
              HasSubstr("expected two different non-empty names"));
  EXPECT_EQ(test::inputErrorOf([] { (void)twoWayAnova(sleep()).row("block"); }),
            "AnovaTable::row: no row named \"block\": expected one of group, ID, Residuals");
}

// ---- Tukey HSD -------------------------------------------------------------------------------

// R: TukeyHSD(aov(breaks ~ wool * tension, data = warpbreaks), "tension")
TEST(TukeyHsd, MatchesRsTukeyHsdOnWarpbreaksTension) {
  // clang-format off
  const TukeyRef expected[] = {
    {"M-L", -9.9999999999999858, -18.819647156951035, -1.1803528430489365, 0.022855398402122584, -18.819647156352943, -1.180352843647027},
    {"H-L", -14.722222222222214, -23.541869379173264, -5.902575065271165, 0.00055953922179385884, -23.541869378575171, -5.9025750658692555},
    {"H-M", -4.7222222222222285, -13.541869379173278, 4.0974249347288207, 0.40494419624975098, -13.541869378575187, 4.0974249341307303},
  };
  // clang-format on
  const TukeyResult result = tukeyHsd(warpbreaks(), Factor::kB);
  expectTukey(result, expected);
  EXPECT_EQ(result.factor, "tension");
  EXPECT_EQ(result.error_term, "Residuals");
  EXPECT_EQ(result.error_df, 48u);
}

// R: TukeyHSD(aov(breaks ~ wool * tension, data = warpbreaks), "wool")
TEST(TukeyHsd, MatchesRsTukeyHsdOnWarpbreaksWool) {
  // clang-format off
  const TukeyRef expected[] = {
    {"B-A", -5.7777777777777821, -11.76457983415056, 0.20902427859499451, 0.058212975956185908, -11.764579833991519, 0.20902427843595461},
  };
  // clang-format on
  expectTukey(tukeyHsd(warpbreaks(), Factor::kA), expected);
}

// R: TukeyHSD(aov(yield ~ N * block, data = npk), "block")
TEST(TukeyHsd, MatchesRsTukeyHsdOnNpkBlocks) {
  // clang-format off
  const TukeyRef expected[] = {
    {"2-1", 3.4250000000000043, -7.3128261244755421, 14.162826124475551, 0.88356910626596452, -7.3128261245711901, 14.162826124571199},
    {"3-1", 6.75, -3.9878261244755464, 17.487826124475546, 0.34303396895506377, -3.9878261245711943, 17.487826124571193},
    {"4-1", -3.8999999999999986, -14.637826124475545, 6.8378261244755478, 0.81947831518137404, -14.637826124571193, 6.8378261245711958},
    {"5-1", -3.5, -14.237826124475546, 7.2378261244755464, 0.87436594199227258, -14.237826124571194, 7.2378261245711943},
    {"6-1", 2.3250000000000028, -8.4128261244755436, 13.062826124475549, 0.9745526767885806, -8.4128261245711915, 13.062826124571197},
    {"3-2", 3.3249999999999957, -7.4128261244755507, 14.062826124475542, 0.89526378287255681, -7.4128261245711986, 14.06282612457119},
    {"4-2", -7.3250000000000028, -18.062826124475549, 3.4128261244755436, 0.26865353733467645, -18.062826124571195, 3.4128261245711915},
    {"5-2", -6.9250000000000043, -17.662826124475551, 3.8128261244755421, 0.319026714890706, -17.662826124571197, 3.8128261245711901},
    {"6-2", -1.1000000000000014, -11.837826124475548, 9.637826124475545, 0.99918299598180926, -11.837826124571196, 9.6378261245711929},
    {"4-3", -10.649999999999999, -21.387826124475545, 0.087826124475547829, 0.052352477331671254, -21.387826124571191, 0.087826124571195763},
    {"5-3", -10.25, -20.987826124475546, 0.48782612447554641, 0.064488457516908904, -20.987826124571193, 0.48782612457119434},
    {"6-3", -4.4249999999999972, -15.162826124475544, 6.3128261244755492, 0.73535812843548209, -15.162826124571191, 6.3128261245711972},
    {"5-4", 0.39999999999999858, -10.337826124475548, 11.137826124475545, 0.99999437387064827, -10.337826124571196, 11.137826124571193},
    {"6-4", 6.2250000000000014, -4.512826124475545, 16.962826124475548, 0.42187651368861556, -4.5128261245711929, 16.962826124571194},
    {"6-5", 5.8250000000000028, -4.9128261244755436, 16.562826124475549, 0.48797580148826514, -4.9128261245711915, 16.562826124571195},
  };
  // clang-format on
  expectTukey(tukeyHsd(npk(), Factor::kB), expected);
}

// R: TukeyHSD(aov(extra ~ group + ID, data = sleep), "group")
TEST(TukeyHsd, MatchesRsTukeyHsdWithoutReplicates) {
  // clang-format off
  const TukeyRef expected[] = {
    {"2-1", 1.5799999999999996, 0.70011423732371347, 2.4598857626762856, 0.0028328901974274956, 0.70011423672272399, 2.459885763277275},
  };
  // clang-format on
  expectTukey(tukeyHsd(sleep(), Factor::kA), expected);
}

// R: TukeyHSD(aov(y ~ mode + subject, data = d1), "mode")
TEST(TukeyHsd, MatchesRsTukeyHsdOnARandomDesignWithoutReplicates) {
  // clang-format off
  const TukeyRef expected[] = {
    {"PCONTROL-BASIC", 0.98749999999999893, -2.4979942274357185, 4.4729942274357164, 0.84573686670332582, -2.4979942395832553, 4.4729942395832527},
    {"ALPHA-BASIC", 2.3219999999999992, -1.1634942274357183, 5.8074942274357166, 0.26127200076868717, -1.163494239583255, 5.8074942395832529},
    {"NONE-BASIC", 1.0198333333333327, -2.4656608941023848, 4.5053275607690502, 0.83310785038778379, -2.4656609062499215, 4.5053275729165865},
    {"ALPHA-PCONTROL", 1.3345000000000002, -2.1509942274357172, 4.8199942274357177, 0.69289712453119545, -2.150994239583254, 4.819994239583254},
    {"NONE-PCONTROL", 0.032333333333333769, -3.4531608941023837, 3.5178275607690512, 0.99999280105631072, -3.4531609062499204, 3.517827572916588},
    {"NONE-ALPHA", -1.3021666666666665, -4.7876608941023839, 2.183327560769051, 0.7083585761466713, -4.7876609062499202, 2.1833275729165877},
  };
  // clang-format on
  expectTukey(tukeyHsd(random1(), Factor::kA), expected);
}

// R: TukeyHSD(aov(y ~ mode * subject, data = d2), "mode")
TEST(TukeyHsd, MatchesRsTukeyHsdOnARandomDesignWithReplicates) {
  // clang-format off
  const TukeyRef expected[] = {
    {"PCONTROL-BASIC", 0.37916666666666732, -0.51261678867429983, 1.2709501220076345, 0.54630479842361446, -0.51261678866935712, 1.2709501220026918},
    {"ALPHA-BASIC", 0.55058333333333387, -0.34120012200763328, 1.442366788674301, 0.28989331328642187, -0.34120012200269056, 1.4423667886693583},
    {"ALPHA-PCONTROL", 0.17141666666666655, -0.7203667886743006, 1.0632001220076337, 0.88134577970109484, -0.72036678866935788, 1.063200122002691},
  };
  // clang-format on
  expectTukey(tukeyHsd(random2(), Factor::kA), expected);
}

// Subject random: TukeyHSD's formulas with the mode:subject mean square and df, in R:
// means <- tapply(d2$y, d2$mode, mean); se <- sqrt(s[["Mean Sq"]][3] / 2 * (2 / 12));
// d <- means[j] - means[i]; d -/+ q * se with q the accurate 0.95 quantile for (3, 6);
// ptukey(abs(d) / se, 3, 6, lower.tail = FALSE)
TEST(TukeyHsd, UsesTheInteractionAsErrorWhenBIsRandom) {
  struct Ref {
    const char* comparison;
    double diff, lower, upper, p_adjusted;
  };
  // clang-format off
  const Ref expected[] = {
    {"PCONTROL-BASIC", 0.37916666666666643, -0.49112710633285683, 1.2494604396661897, 0.42775943246953319},
    {"ALPHA-BASIC", 0.55058333333333298, -0.31971043966619028, 1.4208771063328562, 0.20780221921024933},
    {"ALPHA-PCONTROL", 0.17141666666666655, -0.69887710633285671, 1.0417104396661898, 0.82307354160507862},
  };
  // clang-format on
  const TukeyResult result = tukeyHsd(random2(), Factor::kA, {.b_random = true});
  EXPECT_EQ(result.error_term, "mode:subject");
  EXPECT_EQ(result.error_df, 6u);
  ASSERT_EQ(result.comparisons.size(), std::size(expected));
  for (std::size_t r = 0; r < std::size(expected); ++r) {
    const TukeyComparison& c = result.comparisons[r];
    EXPECT_EQ(c.comparison, expected[r].comparison);
    expectRel(c.diff, expected[r].diff, "diff");
    expectRel(c.lower, expected[r].lower, "lwr");
    expectRel(c.upper, expected[r].upper, "upr");
    expectRel(c.p_adjusted, expected[r].p_adjusted, "p adj");
  }
}

TEST(TukeyHsd, RefusesAConfidenceOutsideZeroToOneAndTooFewErrorDf) {
  EXPECT_EQ(test::inputErrorOf([] { (void)tukeyHsd(sleep(), Factor::kA, {}, 1.0); }),
            "tukeyHsd: confidence: expected a level in (0, 1), got 1");
  // 2 x 2 without replicates: the residual has 1 degree of freedom.
  TwoWayData d;
  d.a = {"x", "x", "y", "y"};
  d.b = {"p", "q", "p", "q"};
  d.y = {1.0, 2.0, 4.0, 3.5};
  EXPECT_EQ(test::inputErrorOf([&] { (void)tukeyHsd(d, Factor::kA); }),
            "tukeyHsd: error term Residuals has 1 degree(s) of freedom: expected at least 2");
}

// ---- Studentized range distribution ----------------------------------------------------------

// R: ptukey(q, k, df) and ptukey(q, k, df, lower.tail = FALSE).
TEST(StudentizedRange, CdfAndUpperTailMatchRsPtukey) {
  struct Ref {
    double q;
    int groups;
    double df, cdf, upper_tail;
  };
  // clang-format off
  const Ref expected[] = {
    {0.5, 2, 2, 0.24254212290936839, 0.75745787709063161},
    {2.5, 2, 2, 0.78090134718561421, 0.21909865281438579},
    {4, 2, 2, 0.89447937826819146, 0.10552062173180854},
    {7, 2, 2, 0.96161604530881928, 0.038383954691180722},
    {0.5, 2, 12, 0.27019274031878693, 0.72980725968121307},
    {2.5, 2, 12, 0.89750680796075222, 0.10249319203924778},
    {4, 2, 12, 0.98477990696626272, 0.015220093033737281},
    {7, 2, 12, 0.99966347670689659, 0.00033652329310340789},
    {0.5, 2, 48, 0.27477819686209248, 0.72522180313790752},
    {2.5, 2, 48, 0.91654407837682361, 0.083455921623176388},
    {4, 2, 48, 0.99319432412428421, 0.0068056758757157887},
    {7, 2, 48, 0.99999043542572408, 9.5645742759220553e-06},
    {0.5, 2, 1000, 0.27625186822760534, 0.72374813177239461},
    {2.5, 2, 1000, 0.92259522390009485, 0.077404776099905148},
    {4, 2, 1000, 0.99522881416243947, 0.0047711858375605321},
    {7, 2, 1000, 0.99999912834032267, 8.7165967732616423e-07},
    {0.5, 2, kInf, 0.27632639016824834, 0.72367360983175166},
    {2.5, 2, kInf, 0.9229001282564584, 0.077099871743541604},
    {4, 2, kInf, 0.99532226501894938, 0.0046777349810506186},
    {7, 2, kInf, 0.99999925690162605, 7.4309837394537226e-07},
    {0.5, 3, 2, 0.064443205571919182, 0.93555679442808082},
    {2.5, 3, 2, 0.63165804463842756, 0.36834195536157244},
    {4, 3, 2, 0.81427846257631853, 0.18572153742368147},
    {7, 3, 2, 0.93063455499959435, 0.069365445000405646},
    {0.5, 3, 12, 0.06620898004617283, 0.93379101995382718},
    {2.5, 3, 12, 0.77840010906977763, 0.22159989093022237},
    {4, 3, 12, 0.96235523782880417, 0.037644762171195834},
    {7, 3, 12, 0.99909323837299369, 0.00090676162700631391},
    {0.5, 3, 48, 0.066485264144020617, 0.93351473585597944},
    {2.5, 3, 48, 0.80870863993221576, 0.19129136006778424},
    {4, 3, 48, 0.98165930468037865, 0.018340695319621347},
    {7, 3, 48, 0.99997184731482081, 2.815268517919467e-05},
    {0.5, 3, 1000, 0.066573592890988284, 0.9334264071090117},
    {2.5, 3, 1000, 0.81896527659271168, 0.18103472340728832},
    {4, 3, 1000, 0.9867716923831521, 0.013228307616847901},
    {7, 3, 1000, 0.99999739442178559, 2.605578214409654e-06},
    {0.5, 3, kInf, 0.066578054864695618, 0.93342194513530441},
    {2.5, 3, kInf, 0.81949106279330819, 0.18050893720669181},
    {4, 3, kInf, 0.98701233862681514, 0.012987661373184856},
    {7, 3, kInf, 0.99999777773385412, 2.2222661458792814e-06},
    {0.5, 5, 2, 0.0059898314388558858, 0.9940101685611441},
    {2.5, 5, 2, 0.45209755932700085, 0.54790244067299909},
    {4, 5, 2, 0.7045112538219257, 0.2954887461780743},
    {7, 5, 2, 0.88547383203780872, 0.11452616796219128},
    {0.5, 5, 12, 0.0038244112905631285, 0.9961755887094369},
    {2.5, 5, 12, 0.56685421984092332, 0.43314578015907668},
    {4, 5, 12, 0.908728155868743, 0.091271844131256996},
    {7, 5, 12, 0.99747259565079893, 0.0025274043492010678},
    {0.5, 5, 48, 0.003463085349522881, 0.99653691465047711},
    {2.5, 5, 48, 0.5961571732218649, 0.4038428267781351},
    {4, 5, 48, 0.94930038767632596, 0.050699612323674037},
    {7, 5, 48, 0.99990938025999809, 9.061974000190709e-05},
    {0.5, 5, 1000, 0.0033462360033507015, 0.99665376399664929},
    {2.5, 5, 1000, 0.6068936249518706, 0.3931063750481294},
    {4, 5, 1000, 0.96169623801438309, 0.038303761985616913},
    {7, 5, 1000, 0.99999137494100909, 8.625058990907597e-06},
    {0.5, 5, kInf, 0.0033403160555708815, 0.99665968394442905},
    {2.5, 5, kInf, 0.60745723675873387, 0.39254276324126613},
    {4, 5, kInf, 0.96230393177990114, 0.037696068220098855},
    {7, 5, kInf, 0.99999263761013679, 7.3623898632080298e-06},
    {0.5, 10, 2, 4.6644681951003679e-05, 0.99995335531804908},
    {2.5, 10, 2, 0.25936024870550151, 0.74063975129449844},
    {4, 10, 2, 0.55762696503712084, 0.44237303496287916},
    {7, 10, 2, 0.81810196338950503, 0.18189803661049497},
    {0.5, 10, 12, 3.8754331184715477e-06, 0.99999612456688158},
    {2.5, 10, 12, 0.25747090122387084, 0.74252909877612916},
    {4, 10, 12, 0.7729003477535209, 0.2270996522464791},
    {7, 10, 12, 0.99188072723355614, 0.0081192727664438635},
    {0.5, 10, 48, 1.8901639400250427e-06, 0.99999810983605997},
    {2.5, 10, 48, 0.24880078755610008, 0.75119921244389998},
    {4, 10, 48, 0.84394278836840642, 0.15605721163159358},
    {7, 10, 48, 0.99962175653323582, 0.00037824346676418319},
    {0.5, 10, 1000, 1.4343355225409524e-06, 0.99999856566447742},
    {2.5, 10, 1000, 0.24454369955516939, 0.75545630044483059},
    {4, 10, 1000, 0.87167742387813318, 0.12832257612186682},
    {7, 10, 1000, 0.99996181199757339, 3.8188002426609025e-05},
    {0.5, 10, kInf, 1.4133805283207629e-06, 0.99999858661947161},
    {2.5, 10, kInf, 0.24430255792427957, 0.75569744207572043},
    {4, 10, kInf, 0.87314786764908858, 0.12685213235091142},
    {7, 10, kInf, 0.99996734081896654, 3.2659181033456441e-05},
    {0.5, 20, 2, 0, 1},
    {2.5, 20, 2, 0.13624319508452454, 0.86375680491547546},
    {4, 20, 2, 0.42823836218171357, 0.57176163781828637},
    {7, 20, 2, 0.74901591111169219, 0.25098408888830781},
    {0.5, 20, 12, 0, 1},
    {2.5, 20, 12, 0.067713974022957785, 0.93228602597704224},
    {4, 20, 12, 0.56897345200710026, 0.43102654799289974},
    {7, 20, 12, 0.97844128479389791, 0.021558715206102086},
    {0.5, 20, 48, 0, 1},
    {2.5, 20, 48, 0.041510888931837346, 0.95848911106816259},
    {4, 20, 48, 0.63065706011497524, 0.36934293988502476},
    {7, 20, 48, 0.9985852807704757, 0.0014147192295242972},
    {0.5, 20, 1000, 0, 1},
    {2.5, 20, 1000, 0.031449897782847104, 0.96855010221715288},
    {4, 20, 1000, 0.66211610183366787, 0.33788389816633213},
    {7, 20, 1000, 0.99984335925605949, 0.00015664074394050598},
    {0.5, 20, kInf, 0, 1},
    {2.5, 20, kInf, 0.030920638709215152, 0.96907936129078487},
    {4, 20, kInf, 0.6639765605852308, 0.3360234394147692},
    {7, 20, kInf, 0.9998656082005335, 0.00013439179946650448},
  };
  // clang-format on
  for (const Ref& e : expected) {
    const std::string what = fmt::format("q {} k {} df {}", e.q, e.groups, e.df);
    // Absolute slack of 1e-13 on top of 1e-8 relative: the upper tail is 1 - cdf, and the
    // two programs' normal CDFs and lgamma differ in the last bits (~1e-15 absolute).
    EXPECT_NEAR(studentizedRangeCdf(e.q, e.groups, e.df), e.cdf, kAnovaRelTol * e.cdf + 1e-13) << what;
    EXPECT_NEAR(studentizedRangeUpperTail(e.q, e.groups, e.df), e.upper_tail,
                kAnovaRelTol * e.upper_tail + 1e-13)
        << what;
  }
}

// R: uniroot(function(x) ptukey(x, k, df) - p, c(0.01, 200), tol = 1e-15)$root, and R's
// qtukey(p, k, df) (only good to ~1e-7 relative, so compared more loosely).
TEST(StudentizedRange, QuantileInvertsTheCdfAsRDoes) {
  struct Ref {
    double p;
    int groups;
    double df, quantile, r_qtukey;
  };
  // clang-format off
  const Ref expected[] = {
    {0.5, 2, 2, 1.1546543214371772, 1.1546543213445166},
    {0.5, 2, 7, 1.0057063473334995, 1.0057066006380122},
    {0.5, 2, 48, 0.96114952252062735, 0.96114965521402074},
    {0.5, 2, 1000, 0.95421962079762834, 0.9542197405865902},
    {0.5, 3, 2, 1.9081785184050695, 1.9081786381388866},
    {0.5, 3, 7, 1.6700913566337987, 1.6700914176581008},
    {0.5, 3, 48, 1.599375426062742, 1.5993754416220418},
    {0.5, 3, 1000, 1.5883408189658985, 1.5883408301477453},
    {0.5, 6, 2, 2.9732889235076025, 2.9732888809844744},
    {0.5, 6, 7, 2.6005671962837824, 2.6005671962695569},
    {0.5, 6, 48, 2.4900134850448929, 2.4900135327917403},
    {0.5, 6, 1000, 2.4725311492294111, 2.4725311492285105},
    {0.5, 10, 2, 3.6450680736042549, 3.6450680735734511},
    {0.5, 10, 7, 3.1857484799342335, 3.1857484845534674},
    {0.5, 10, 48, 3.0478382783765339, 3.0478382792931136},
    {0.5, 10, 1000, 3.025345099369444, 3.0253450996876494},
    {0.90000000000000002, 2, 2, 4.1281827096162393, 4.1281826677123723},
    {0.90000000000000002, 2, 7, 2.6793387583009203, 2.6793387482426896},
    {0.90000000000000002, 2, 48, 2.3719532052771681, 2.3719532052989547},
    {0.90000000000000002, 2, 1000, 2.3283312522109081, 2.3283312522521009},
    {0.90000000000000002, 3, 2, 5.7326489525703197, 5.7326489525409814},
    {0.90000000000000002, 3, 7, 3.4511651400653509, 3.4511651398800778},
    {0.90000000000000002, 3, 48, 2.9733005418743255, 2.9733005418925944},
    {0.90000000000000002, 3, 1000, 2.9057201134612849, 2.9057201135284627},
    {0.90000000000000002, 6, 2, 8.1390855188789555, 8.1390855165810709},
    {0.90000000000000002, 6, 7, 4.5547634526405876, 4.5547634513771138},
    {0.90000000000000002, 6, 48, 3.7784849914805254, 3.7784848532376198},
    {0.90000000000000002, 6, 1000, 3.6662878589575962, 3.6662878590930581},
    {0.90000000000000002, 10, 2, 9.7248967893328651, 9.7248967775210335},
    {0.90000000000000002, 10, 7, 5.2826812766511155, 5.282681276309992},
    {0.90000000000000002, 10, 48, 4.2854033944725742, 4.2854033237875049},
    {0.90000000000000002, 10, 1000, 4.1367686176819491, 4.1367686179654255},
    {0.94999999999999996, 2, 2, 6.0796374187024647, 6.0796374186957944},
    {0.94999999999999996, 2, 7, 3.3440836865204826, 3.3440836864694981},
    {0.94999999999999996, 2, 48, 2.84346694316682, 2.8434669432423569},
    {0.94999999999999996, 2, 1000, 2.775166542083241, 2.7751665423706502},
    {0.94999999999999996, 3, 2, 8.3307826456548533, 8.3307825511898272},
    {0.94999999999999996, 3, 7, 4.1649414923810699, 4.1649414998068295},
    {0.94999999999999996, 3, 48, 3.4202579882125397, 3.420257988444479},
    {0.94999999999999996, 3, 1000, 3.3194448973318624, 3.3194448991600747},
    {0.94999999999999996, 6, 2, 11.733607458593509, 11.73360745858937},
    {0.94999999999999996, 6, 7, 5.3590785657021165, 5.3590785656877973},
    {0.94999999999999996, 6, 48, 4.1972370334950844, 4.1972370341648126},
    {0.94999999999999996, 6, 1000, 4.0379325578254699, 4.0379325836937072},
    {0.94999999999999996, 10, 2, 13.993854035380991, 13.993854035371633},
    {0.94999999999999996, 10, 7, 6.1579437084662967, 6.1579437044766028},
    {0.94999999999999996, 10, 48, 4.6902408860424707, 4.6902408873196659},
    {0.94999999999999996, 10, 1000, 4.4843022647983783, 4.4843024456033715},
    {0.98999999999999999, 2, 2, 13.902104720019903, 13.902104719984681},
    {0.98999999999999999, 2, 7, 4.9490167404177861, 4.9490167403902294},
    {0.98999999999999999, 2, 48, 3.7932093117682415, 3.7932091341068284},
    {0.98999999999999999, 2, 1000, 3.6497382951799313, 3.6497382958574556},
    {0.98999999999999999, 3, 2, 19.015496331183211, 19.015496329474683},
    {0.98999999999999999, 3, 7, 5.9192937840235764, 5.919293784010323},
    {0.98999999999999999, 3, 48, 4.3243339479734155, 4.3243339485671903},
    {0.98999999999999999, 3, 1000, 4.1297250456327337, 4.1297250984187972},
    {0.98999999999999999, 6, 2, 27.756936656693206, 27.756936656322839},
    {0.98999999999999999, 6, 7, 7.3730119968294687, 7.3730119965997316},
    {0.98999999999999999, 6, 48, 5.0523919314257109, 5.0523919478142139},
    {0.98999999999999999, 6, 1000, 4.7706628658153463, 4.7706628684736403},
    {0.98999999999999999, 10, 2, 34.925601863382347, 34.925601863382276},
    {0.98999999999999999, 10, 7, 8.3673753545464642, 8.367375352645313},
    {0.98999999999999999, 10, 48, 5.5221504987028789, 5.5221505826955273},
    {0.98999999999999999, 10, 1000, 5.1734923025968769, 5.1734924525412191},
  };
  // clang-format on
  for (const Ref& e : expected) {
    const std::string what = fmt::format("p {} k {} df {}", e.p, e.groups, e.df);
    const double q = studentizedRangeQuantile(e.p, e.groups, e.df);
    expectRel(q, e.quantile, what, 1e-9);
    expectRel(q, e.r_qtukey, what + " (R qtukey)", 5e-7);
  }
}

TEST(StudentT, QuantileMatchesRsQt) {
  // R 4.2.2: print(qt(c(0.975, 0.975, 0.025, 0.995), c(9, 2, 5, 30)), digits = 17)
  EXPECT_NEAR(analysis::studentTQuantile(0.975, 9), 2.2621571627982049, 1e-13);
  EXPECT_NEAR(analysis::studentTQuantile(0.975, 2), 4.3026527297494619, 1e-13);
  EXPECT_NEAR(analysis::studentTQuantile(0.025, 5), -2.5705818356363150, 1e-13);
  EXPECT_NEAR(analysis::studentTQuantile(0.995, 30), 2.7499956535672254, 1e-13);
  EXPECT_THROW((void)analysis::studentTQuantile(1.0, 5), InputError);
  EXPECT_THROW((void)analysis::studentTQuantile(0.5, 0), InputError);
}

TEST(StudentizedRange, HasTheLimitsOfADistribution) {
  EXPECT_EQ(studentizedRangeCdf(0.0, 3, 10), 0.0);
  EXPECT_EQ(studentizedRangeCdf(-1.0, 3, 10), 0.0);
  EXPECT_EQ(studentizedRangeCdf(kInf, 3, 10), 1.0);
  EXPECT_EQ(studentizedRangeUpperTail(kInf, 3, 10), 0.0);
  // For two groups Q = sqrt(2) |T| with T ~ Student t: at df = infinity, P(Q <= q) =
  // 2 Φ(q / sqrt 2) - 1 = erf(q / 2).
  for (const double q : {0.3, 1.0, 2.5, 5.0}) {
    EXPECT_NEAR(studentizedRangeCdf(q, 2, kInf), std::erf(q / 2.0), 1e-12) << q;
  }
  EXPECT_EQ(test::inputErrorOf([] { (void)studentizedRangeCdf(1.0, 1, 10); }),
            "studentizedRangeCdf: groups: expected at least 2, got 1");
  EXPECT_EQ(test::inputErrorOf([] { (void)studentizedRangeCdf(1.0, 3, 1.5); }),
            "studentizedRangeCdf: df: expected at least 2 (or +infinity), got 1.5");
  EXPECT_EQ(test::inputErrorOf([] { (void)studentizedRangeQuantile(1.0, 3, 10); }),
            "studentizedRangeQuantile: p: expected a probability in (0, 1), got 1");
}

// ---- Descriptive statistics ------------------------------------------------------------------

// R: y <- warpbreaks$breaks[warpbreaks$tension == l]; mean(y); var(y); sd(y)
TEST(DescribeGroups, MatchesRsMeanVarAndSdPerLevel) {
  struct Ref {
    const char* level;
    double mean, variance, sd;
  };
  // clang-format off
  const Ref expected[] = {
    {"L", 36.388888888888886, 270.48692810457516, 16.446486801276897},
    {"M", 26.388888888888889, 83.192810457516345, 9.1210092894107042},
    {"H", 21.666666666666668, 69.764705882352942, 8.3525269159909286},
  };
  // clang-format on
  const auto stats = describeGroups(warpbreaks(), Grouping::kB);
  ASSERT_EQ(stats.size(), std::size(expected));
  for (std::size_t g = 0; g < stats.size(); ++g) {
    EXPECT_EQ(stats[g].b_level, expected[g].level);
    EXPECT_EQ(stats[g].a_level, "");
    EXPECT_EQ(stats[g].stats.count, 18u);
    expectRel(stats[g].stats.mean, expected[g].mean, "mean");
    expectRel(stats[g].stats.variance, expected[g].variance, "variance");
    expectRel(stats[g].stats.sd, expected[g].sd, "sd");
  }
}

TEST(DescribeGroups, ListsCellsAMajorAndSkipsEmptyCells) {
  TwoWayData d;
  d.a = {"x", "y", "x", "x"};
  d.b = {"p", "p", "q", "q"};
  d.y = {1.0, 2.0, 3.0, 5.0};
  const auto cells = describeGroups(d, Grouping::kCells);
  ASSERT_EQ(cells.size(), 3u);  // (y, q) has no observations
  EXPECT_EQ(cells[0].a_level + cells[0].b_level, "xp");
  EXPECT_EQ(cells[1].a_level + cells[1].b_level, "xq");
  EXPECT_EQ(cells[2].a_level + cells[2].b_level, "yp");
  EXPECT_EQ(cells[1].stats.mean, 4.0);
  EXPECT_EQ(cells[1].stats.variance, 2.0);
  EXPECT_TRUE(std::isnan(cells[0].stats.variance));  // one value, as R's var()
  EXPECT_EQ(test::inputErrorOf([] { (void)describe(std::vector<double>{}); }),
            "describe: expected at least 1 value, got 0");
}

// R: var(d1$y[d1$mode == l]) for each mode (one observation per subject).
TEST(InterSubjectVariance, IsTheVarianceOverSubjectsPerModeWithoutReplicates) {
  struct Ref {
    const char* level;
    double variance;
  };
  // clang-format off
  const Ref expected[] = {
    {"BASIC", 5.2791503000000013},
    {"PCONTROL", 3.3958219999999986},
    {"ALPHA", 1.8920267},
    {"NONE", 4.1622234666666689},
  };
  // clang-format on
  const auto variances = interSubjectVariance(random1());
  ASSERT_EQ(variances.size(), std::size(expected));
  for (std::size_t l = 0; l < variances.size(); ++l) {
    EXPECT_EQ(variances[l].level, expected[l].level);
    expectRel(variances[l].variance, expected[l].variance, expected[l].level);
  }
}

// R: cm <- tapply(d2$y, list(d2$mode, d2$subject), mean); var(cm[l, ]) for each mode.
TEST(InterSubjectVariance, IsTheVarianceOfSubjectMeansWithReplicates) {
  struct Ref {
    const char* level;
    double variance;
  };
  // clang-format off
  const Ref expected[] = {
    {"BASIC", 0.41665891666666693},
    {"PCONTROL", 0.34902313888888864},
    {"ALPHA", 0.52622640740740756},
  };
  // clang-format on
  const auto variances = interSubjectVariance(random2());
  ASSERT_EQ(variances.size(), std::size(expected));
  for (std::size_t l = 0; l < variances.size(); ++l) {
    EXPECT_EQ(variances[l].level, expected[l].level);
    expectRel(variances[l].variance, expected[l].variance, expected[l].level);
  }
}

// R's PlantGrowth (anova_reference.R): aov(weight ~ group) and TukeyHSD, whole and with rows
// 1, 2 and 11 left out (groups of 8, 9 and 10: the Tukey–Kramer standard error).
OneWayData plantGrowth(bool unequal) {
  const std::vector<double> weight{4.17, 5.58, 5.18, 6.11, 4.50, 4.61, 5.17, 4.53, 5.33, 5.14,
                                   4.81, 4.17, 4.41, 3.59, 5.87, 3.83, 6.03, 4.89, 4.32, 4.69,
                                   6.31, 5.12, 5.54, 5.50, 5.37, 5.29, 4.92, 6.15, 5.80, 5.26};
  OneWayData data;
  for (std::size_t i = 0; i < weight.size(); ++i) {
    if (unequal && (i == 0 || i == 1 || i == 10)) continue;
    data.group.push_back(i < 10 ? "ctrl" : i < 20 ? "trt1" : "trt2");
    data.y.push_back(weight[i]);
  }
  return data;
}

TEST(OneWayAnova, MatchesRsAovAndTukeyHsdOnPlantGrowth) {
  const AnovaTable table = oneWayAnova(plantGrowth(false));
  const AnovaRow& group = table.row("group");
  EXPECT_EQ(group.df, 2u);
  EXPECT_EQ(table.row("Residuals").df, 27u);
  EXPECT_NEAR(group.sum_sq, 3.7663399999999987, 1e-12);
  EXPECT_NEAR(table.row("Residuals").sum_sq, 10.492089999999997, 1e-12);
  EXPECT_NEAR(group.f, 4.8460878623801351, 1e-12);
  EXPECT_NEAR(group.p, 0.015909958325622937, 1e-12);
  EXPECT_NEAR(group.partial_eta_sq, 3.7663399999999987 / (3.7663399999999987 + 10.492089999999997), 1e-14);
  const TukeyResult tukey = tukeyHsdOneWay(plantGrowth(false));
  ASSERT_EQ(tukey.comparisons.size(), 3u);
  const std::array<const char*, 3> names{"trt1-ctrl", "trt2-ctrl", "trt2-trt1"};
  const std::array<double, 3> diff{-0.37100000000000044, 0.49399999999999977, 0.86500000000000021};
  const std::array<double, 3> lower{-1.0622160514104588, -0.19721605141045861, 0.17378394858954183};
  const std::array<double, 3> p{0.39087114420212465, 0.19799599129970824, 0.012006423979452729};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(tukey.comparisons[i].comparison, names[i]);
    EXPECT_NEAR(tukey.comparisons[i].diff, diff[i], 1e-12);
    EXPECT_NEAR(tukey.comparisons[i].lower, lower[i], 1e-6) << "R's qtukey stops near 1e-8 relative";
    EXPECT_NEAR(tukey.comparisons[i].p_adjusted, p[i], 1e-9);
  }
}

TEST(OneWayAnova, MatchesRWithUnequalGroups) {
  const AnovaTable table = oneWayAnova(plantGrowth(true));
  const AnovaRow& group = table.row("group");
  EXPECT_NEAR(group.f, 4.7034427032238879, 1e-12);
  EXPECT_NEAR(group.p, 0.018901795160526171, 1e-12);
  const TukeyResult tukey = tukeyHsdOneWay(plantGrowth(true));
  const std::array<double, 3> diff{-0.4268055555555561, 0.45474999999999977, 0.88155555555555587};
  const std::array<double, 3> p{0.35543677877146884, 0.29472035384364115, 0.014214261295000696};
  const std::array<double, 3> lower{-1.1867052218052381, -0.28705422123104407, 0.16301119194710945};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(tukey.comparisons[i].diff, diff[i], 1e-12);
    EXPECT_NEAR(tukey.comparisons[i].p_adjusted, p[i], 1e-9);
    EXPECT_NEAR(tukey.comparisons[i].lower, lower[i], 1e-6);
  }
}

TEST(OneWayAnova, RefusesOneGroupAndNonFiniteData) {
  OneWayData one{"group", {"a", "a", "a"}, {1.0, 2.0, 3.0}};
  EXPECT_THROW((void)oneWayAnova(one), InputError);
  OneWayData bad{"group", {"a", "b", "b"}, {1.0, std::nan(""), 3.0}};
  EXPECT_THROW((void)oneWayAnova(bad), InputError);
  OneWayData too_few{"group", {"a", "b"}, {1.0, 2.0}};
  EXPECT_THROW((void)oneWayAnova(too_few), InputError);
}

// No variance within the groups: Tukey's comparisons still come (a power analysis counts a p it
// cannot give as not significant), a difference certain (p 0), none telling nothing (NaN).
TEST(OneWayAnova, TukeyWithoutErrorVarianceGivesZeroOrNaNInsteadOfFailing) {
  const OneWayData flat{"group", {"a", "a", "b", "b", "c", "c"}, {1.0, 1.0, 1.0, 1.0, 2.0, 2.0}};
  const TukeyResult t = tukeyHsdOneWay(flat);
  ASSERT_EQ(t.comparisons.size(), 3u);
  for (const auto& c : t.comparisons) {
    if (c.diff == 0.0) {
      EXPECT_TRUE(std::isnan(c.p_adjusted)) << c.comparison;
    } else {
      EXPECT_EQ(c.p_adjusted, 0.0) << c.comparison;
    }
  }
}

}  // namespace
}  // namespace hattr::analysis
