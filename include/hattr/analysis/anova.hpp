#pragma once
/// Balanced two-way analysis of variance, Tukey's honest significant differences and
/// descriptive statistics: the paper's evaluation of training modes (factor A, e.g. mode:
/// BASIC, PCONTROL, ALPHA) across subjects (factor B) on a response such as a DTW cost
/// (section 5.2). Results follow R's summary(aov()) and TukeyHSD(); docs/analysis.md gives
/// the formulas and how the tests' reference values were made with R.
///
/// Responses are in the caller's unit; sums of squares and mean squares in its square.
/// Levels are ordered by first appearance in the data (R orders them alphabetically unless
/// told otherwise; list the observations in the order you want the levels).
///
/// Offline analysis code: any thread but the servo thread; thread-safe (no shared state).
/// Bad input throws hattr::InputError naming the function, the row or cell, what was
/// expected and what was found.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hattr::analysis {

/// A table of observations: row r has level a[r] of factor A, level b[r] of factor B and
/// response y[r]. The three columns have equal lengths.
struct TwoWayData {
  std::string a_name = "A";  ///< factor A's name, used in the output ("mode")
  std::string b_name = "B";  ///< factor B's name ("subject")
  std::vector<std::string> a;
  std::vector<std::string> b;
  std::vector<double> y;
};

/// One of the two factors.
enum class Factor { kA, kB };

struct AnovaOptions {
  /// Factor B is random (subjects drawn from a population), A fixed: the mixed model.
  /// With replicates, A is tested against the A:B mean square (df (a-1)(b-1)); B and A:B
  /// against the residual mean square (the restricted mixed model). Without replicates
  /// every term is tested against the residual, as in the fixed model.
  bool b_random = false;
};

/// One row of the ANOVA table, as in R's summary(aov()).
struct AnovaRow {
  std::string source;           ///< "mode", "subject", "mode:subject" or "Residuals"
  std::size_t df = 0;           ///< degrees of freedom
  double sum_sq = 0.0;          ///< sum of squares [response unit²]
  double mean_sq = 0.0;         ///< sum_sq / df
  double f = 0.0;               ///< mean_sq / error mean square; NaN on the Residuals row
  double p = 0.0;               ///< P(F(df, error df) > f); NaN on the Residuals row
  double partial_eta_sq = 0.0;  ///< sum_sq / (sum_sq + error sum_sq); NaN on Residuals
  std::string error_term;       ///< the row this one is tested against; empty on Residuals
};

/// A two-way ANOVA table.
struct AnovaTable {
  /// A, B, A:B (with replicates only), Residuals, in that order.
  std::vector<AnovaRow> rows;
  std::size_t replicates = 0;  ///< observations per cell
  std::vector<std::string> a_levels;
  std::vector<std::string> b_levels;
  /// The row named `source`. Throws InputError if there is none, listing the names.
  [[nodiscard]] const AnovaRow& row(std::string_view source) const;
};

/// Balanced two-way ANOVA. With replicates (n > 1 per cell): model A + B + A:B; without
/// (n = 1): the additive model A + B, whose residual is the A:B interaction. Each factor
/// needs at least 2 levels. Throws InputError on columns of different lengths, an empty
/// level name, equal or empty factor names, a non-finite response, fewer than 2 levels,
/// or an unbalanced design (a missing cell or differing replicate counts: the message
/// names the offending cells).
[[nodiscard]] AnovaTable twoWayAnova(const TwoWayData& data, const AnovaOptions& options = {});

/// One Tukey HSD comparison, as a row of R's TukeyHSD(): level - other_level.
struct TukeyComparison {
  std::string comparison;  ///< "level-other_level", R's row name
  std::string level;
  std::string other_level;
  double diff = 0.0;        ///< mean(level) - mean(other_level) [response unit]
  double lower = 0.0;       ///< lower end of the family-wise confidence interval
  double upper = 0.0;       ///< upper end
  double p_adjusted = 0.0;  ///< family-wise adjusted p-value
};

/// Tukey HSD between the levels of one factor.
struct TukeyResult {
  std::string factor;        ///< the factor's name
  double confidence = 0.95;  ///< family-wise confidence level of the intervals
  std::string error_term;    ///< the ANOVA row used as error ("Residuals" or "A:B")
  double error_mean_sq = 0.0;
  std::size_t error_df = 0;
  /// Pairs of levels i < j in level order, (1,0), (2,0), ..., (2,1), ...: R's order.
  std::vector<TukeyComparison> comparisons;
};

/// Tukey's HSD for all pairs of levels of `factor`, like R's TukeyHSD(aov(y ~ A * B))
/// (with replicates) or TukeyHSD(aov(y ~ A + B)) (without): differences of the level
/// means, confidence bounds diff ± q(confidence; k, df) * sqrt(MSE / 2 * (1/n_i + 1/n_j))
/// and p-values P(Q > |diff| / that standard error). The error term is the one that tests
/// the factor in twoWayAnova() (A:B for A when B is random and replicated, else the
/// residual). Throws as twoWayAnova(), and InputError unless 0 < confidence < 1 or if
/// the error term has fewer than 2 degrees of freedom.
[[nodiscard]] TukeyResult tukeyHsd(const TwoWayData& data, Factor factor,
                                   const AnovaOptions& options = {}, double confidence = 0.95);

/// Count, mean, sample variance (n - 1 denominator, as R's var()) and standard deviation
/// of some values. variance and sd are NaN for a single value.
struct Descriptive {
  std::size_t count = 0;
  double mean = 0.0;
  double variance = 0.0;
  double sd = 0.0;
};

/// Descriptive statistics of `values`. Throws InputError if empty or not all finite.
[[nodiscard]] Descriptive describe(std::span<const double> values);

/// Groups for describeGroups().
enum class Grouping {
  kA,      ///< one group per level of A
  kB,      ///< one group per level of B
  kCells,  ///< one group per (A, B) cell that has observations
};

/// Descriptive statistics of one group of observations.
struct GroupStats {
  std::string a_level;  ///< empty when grouping by B only
  std::string b_level;  ///< empty when grouping by A only
  Descriptive stats;
};

/// Mean, variance and sd of the response per group, groups in level order (cells: A
/// major, B minor). Needs no balance. Throws InputError on columns of different lengths
/// or a non-finite response.
[[nodiscard]] std::vector<GroupStats> describeGroups(const TwoWayData& data, Grouping grouping);

/// The inter-subject variance of one level of A (one mode).
struct LevelVariance {
  std::string level;
  double variance = 0.0;
};

/// Per level of A (mode), the overall inter-subject variance: the sample variance over
/// the levels of B (subjects) of the subject's mean response under that mode. Without
/// replicates that is the variance of the mode's observations. NaN when a mode has fewer
/// than 2 subjects. Needs no balance. Throws as describeGroups().
[[nodiscard]] std::vector<LevelVariance> interSubjectVariance(const TwoWayData& data);

/// One-way data: a group level and a response per observation (e.g. each subject's mean cost
/// and their group, in a between-subjects design).
struct OneWayData {
  std::string factor = "group";  ///< the factor's name, used in the output
  std::vector<std::string> group;
  std::vector<double> y;
};

/// One-way ANOVA, like R's anova(lm(y ~ group)) (groups may differ in size): rows the factor
/// and Residuals, levels in order of first appearance. Throws InputError on columns of
/// different lengths, an empty level name, a non-finite response, fewer than 2 levels, or
/// fewer than one residual degree of freedom.
[[nodiscard]] AnovaTable oneWayAnova(const OneWayData& data);

/// Tukey's HSD between the groups of a one-way design, like R's TukeyHSD(aov(y ~ group)):
/// the Tukey–Kramer standard error sqrt(MSE / 2 (1/n_i + 1/n_j)) for unequal groups. Throws
/// as oneWayAnova(), and InputError unless 0 < confidence < 1 or the residual has at least 2
/// degrees of freedom.
[[nodiscard]] TukeyResult tukeyHsdOneWay(const OneWayData& data, double confidence = 0.95);

}  // namespace hattr::analysis
