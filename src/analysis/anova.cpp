// Balanced two-way ANOVA from cell, level and grand means; Tukey HSD; descriptive
// statistics. Formulas are in docs/analysis.md.

#include "hattr/analysis/anova.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>

#include <boost/math/distributions/fisher_f.hpp>

#include "hattr/analysis/studentized_range.hpp"
#include "hattr/core/error.hpp"

namespace hattr::analysis {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::string_view kResiduals = "Residuals";

// Columns of equal length, non-empty level names, finite responses.
void checkColumns(std::string_view function, const TwoWayData& data) {
  HATTR_THROW_UNLESS(data.a.size() == data.y.size() && data.b.size() == data.y.size(),
                     "{}: columns differ in length: expected equal lengths, got {} ({}), {} ({}) "
                     "and {} (response)",
                     function, data.a.size(), data.a_name, data.b.size(), data.b_name,
                     data.y.size());
  for (std::size_t r = 0; r < data.y.size(); ++r) {
    HATTR_THROW_UNLESS(std::isfinite(data.y[r]),
                       "{}: row {}: response: expected a finite number, got {}", function, r,
                       data.y[r]);
    HATTR_THROW_UNLESS(!data.a[r].empty(), "{}: row {}: {}: expected a level name, got \"\"",
                       function, r, data.a_name);
    HATTR_THROW_UNLESS(!data.b[r].empty(), "{}: row {}: {}: expected a level name, got \"\"",
                       function, r, data.b_name);
  }
}

// Levels in order of first appearance and each row's level index.
struct LevelIndex {
  std::vector<std::string> levels;
  std::vector<std::size_t> of_row;
};

LevelIndex indexLevels(const std::vector<std::string>& column) {
  LevelIndex index;
  std::unordered_map<std::string, std::size_t> position;
  for (const auto& level : column) {
    const auto [it, inserted] = position.try_emplace(level, index.levels.size());
    if (inserted) index.levels.push_back(level);
    index.of_row.push_back(it->second);
  }
  return index;
}

// Sample statistics of values known to be finite and non-empty.
Descriptive describeUnchecked(std::span<const double> values) {
  Descriptive d;
  d.count = values.size();
  double sum = 0.0;
  for (const double v : values) sum += v;
  d.mean = sum / static_cast<double>(d.count);
  if (d.count < 2) {
    d.variance = d.sd = kNaN;
    return d;
  }
  double squares = 0.0;
  for (const double v : values) squares += (v - d.mean) * (v - d.mean);
  d.variance = squares / static_cast<double>(d.count - 1);
  d.sd = std::sqrt(d.variance);
  return d;
}

// The sums of squares of a balanced design.
struct BalancedFit {
  LevelIndex a;
  LevelIndex b;
  std::size_t replicates = 0;
  std::vector<double> a_mean;
  std::vector<double> b_mean;
  double ss_a = 0.0;
  double ss_b = 0.0;
  double ss_ab = 0.0;      // interaction; the residual when replicates == 1
  double ss_within = 0.0;  // within cells; 0 when replicates == 1
};

// Refuses an unbalanced design, naming up to 12 offending cells.
void checkBalance(std::string_view function, const TwoWayData& data, const BalancedFit& fit,
                  const std::vector<std::size_t>& counts) {
  // The expected replicate count is the most common non-zero one (ties: the smaller).
  std::map<std::size_t, std::size_t> frequency;
  for (const std::size_t c : counts) {
    if (c > 0) ++frequency[c];
  }
  std::size_t expected = 0;
  std::size_t best = 0;
  for (const auto& [count, times] : frequency) {
    if (times > best) {
      best = times;
      expected = count;
    }
  }
  std::string offenders;
  std::size_t listed = 0;
  std::size_t bad = 0;
  for (std::size_t i = 0; i < fit.a.levels.size(); ++i) {
    for (std::size_t j = 0; j < fit.b.levels.size(); ++j) {
      const std::size_t c = counts[i * fit.b.levels.size() + j];
      if (c == expected) continue;
      ++bad;
      if (listed++ == 12) continue;
      const std::string what = c == 0         ? "missing"
                               : c > expected ? fmt::format("{} extra", c - expected)
                                              : fmt::format("{} too few", expected - c);
      offenders += fmt::format("{}{}={}, {}={}: {} ({})", offenders.empty() ? "" : "; ",
                               data.a_name, fit.a.levels[i], data.b_name, fit.b.levels[j], c, what);
    }
  }
  if (bad > 12) offenders += fmt::format("; and {} more", bad - 12);
  HATTR_THROW_UNLESS(bad == 0,
                     "{}: unbalanced design: expected {} observations in each of the {} x {} "
                     "cells {} x {}, got {}",
                     function, expected, fit.a.levels.size(), fit.b.levels.size(), data.a_name,
                     data.b_name, offenders);
}

BalancedFit fitBalanced(std::string_view function, const TwoWayData& data) {
  checkColumns(function, data);
  HATTR_THROW_UNLESS(!data.a_name.empty() && !data.b_name.empty() && data.a_name != data.b_name,
                     "{}: factor names: expected two different non-empty names, got \"{}\" and "
                     "\"{}\"",
                     function, data.a_name, data.b_name);
  BalancedFit fit;
  fit.a = indexLevels(data.a);
  fit.b = indexLevels(data.b);
  const std::size_t na = fit.a.levels.size();
  const std::size_t nb = fit.b.levels.size();
  HATTR_THROW_UNLESS(na >= 2 && nb >= 2,
                     "{}: expected at least 2 levels of each factor, got {} of {} and {} of {}",
                     function, na, data.a_name, nb, data.b_name);

  // Cell counts and sums; the design must be balanced.
  std::vector<std::size_t> counts(na * nb, 0);
  std::vector<double> cell_sum(na * nb, 0.0);
  for (std::size_t r = 0; r < data.y.size(); ++r) {
    const std::size_t cell = fit.a.of_row[r] * nb + fit.b.of_row[r];
    ++counts[cell];
    cell_sum[cell] += data.y[r];
  }
  checkBalance(function, data, fit, counts);
  fit.replicates = counts[0];
  const auto n = static_cast<double>(fit.replicates);

  // Cell, level and grand means.
  std::vector<double> cell_mean(na * nb);
  for (std::size_t c = 0; c < cell_mean.size(); ++c) cell_mean[c] = cell_sum[c] / n;
  double total = 0.0;
  for (const double y : data.y) total += y;
  const double grand = total / static_cast<double>(data.y.size());
  fit.a_mean.assign(na, 0.0);
  fit.b_mean.assign(nb, 0.0);
  for (std::size_t i = 0; i < na; ++i) {
    for (std::size_t j = 0; j < nb; ++j) {
      fit.a_mean[i] += cell_sum[i * nb + j];
      fit.b_mean[j] += cell_sum[i * nb + j];
    }
  }
  for (auto& m : fit.a_mean) m /= static_cast<double>(nb) * n;
  for (auto& m : fit.b_mean) m /= static_cast<double>(na) * n;

  // Sums of squared deviations.
  for (const double m : fit.a_mean) fit.ss_a += (m - grand) * (m - grand);
  fit.ss_a *= static_cast<double>(nb) * n;
  for (const double m : fit.b_mean) fit.ss_b += (m - grand) * (m - grand);
  fit.ss_b *= static_cast<double>(na) * n;
  for (std::size_t i = 0; i < na; ++i) {
    for (std::size_t j = 0; j < nb; ++j) {
      const double e = cell_mean[i * nb + j] - fit.a_mean[i] - fit.b_mean[j] + grand;
      fit.ss_ab += e * e;
    }
  }
  fit.ss_ab *= n;
  for (std::size_t r = 0; r < data.y.size(); ++r) {
    const double e = data.y[r] - cell_mean[fit.a.of_row[r] * nb + fit.b.of_row[r]];
    fit.ss_within += e * e;
  }
  return fit;
}

// P(F(df1, df2) > f); 0 for f = +inf, NaN for NaN.
double upperTailF(double f, std::size_t df1, std::size_t df2) {
  if (std::isnan(f)) return kNaN;
  if (std::isinf(f)) return 0.0;
  const boost::math::fisher_f dist(static_cast<double>(df1), static_cast<double>(df2));
  return boost::math::cdf(boost::math::complement(dist, f));
}

AnovaRow effectRow(std::string source, std::size_t df, double ss, const AnovaRow& error) {
  AnovaRow row;
  row.source = std::move(source);
  row.df = df;
  row.sum_sq = ss;
  row.mean_sq = ss / static_cast<double>(df);
  row.f = row.mean_sq / error.mean_sq;
  row.p = upperTailF(row.f, df, error.df);
  row.partial_eta_sq = ss / (ss + error.sum_sq);
  row.error_term = error.source;
  return row;
}

AnovaTable tableOf(const TwoWayData& data, const BalancedFit& fit, const AnovaOptions& options) {
  const std::size_t df_a = fit.a.levels.size() - 1;
  const std::size_t df_b = fit.b.levels.size() - 1;
  const std::size_t df_ab = df_a * df_b;
  const bool replicated = fit.replicates > 1;
  AnovaTable table;
  table.replicates = fit.replicates;
  table.a_levels = fit.a.levels;
  table.b_levels = fit.b.levels;

  AnovaRow residual;
  residual.source = kResiduals;
  residual.df =
      replicated ? fit.a.levels.size() * fit.b.levels.size() * (fit.replicates - 1) : df_ab;
  residual.sum_sq = replicated ? fit.ss_within : fit.ss_ab;
  residual.mean_sq = residual.sum_sq / static_cast<double>(residual.df);
  residual.f = residual.p = residual.partial_eta_sq = kNaN;

  if (!replicated) {
    // Additive model: the interaction is the residual.
    table.rows = {effectRow(data.a_name, df_a, fit.ss_a, residual),
                  effectRow(data.b_name, df_b, fit.ss_b, residual), residual};
    return table;
  }
  const AnovaRow interaction =
      effectRow(fmt::format("{}:{}", data.a_name, data.b_name), df_ab, fit.ss_ab, residual);
  // Mixed model: A against A:B; fixed model: everything against the residual.
  const AnovaRow& a_error = options.b_random ? interaction : residual;
  table.rows = {effectRow(data.a_name, df_a, fit.ss_a, a_error),
                effectRow(data.b_name, df_b, fit.ss_b, residual), interaction, residual};
  return table;
}

}  // namespace

const AnovaRow& AnovaTable::row(std::string_view source) const {
  const auto it =
      std::find_if(rows.begin(), rows.end(), [&](const AnovaRow& r) { return r.source == source; });
  if (it != rows.end()) return *it;
  std::string names;
  for (const auto& r : rows) names += (names.empty() ? "" : ", ") + r.source;
  throw InputError(
      fmt::format("AnovaTable::row: no row named \"{}\": expected one of {}", source, names));
}

AnovaTable twoWayAnova(const TwoWayData& data, const AnovaOptions& options) {
  return tableOf(data, fitBalanced("twoWayAnova", data), options);
}

namespace {

/// Every pair of levels i < j, as R's TukeyHSD lists them: mean difference, the family-wise
/// interval and adjusted p, with the Tukey–Kramer standard error sqrt(MSE / 2 (1/n_i + 1/n_j))
/// (equal n: Tukey's own). `error` carries the error mean square and degrees of freedom.
std::vector<TukeyComparison> tukeyComparisons(const std::vector<std::string>& levels, const std::vector<double>& means,
                                              const std::vector<double>& counts, const TukeyResult& error,
                                              double confidence) {
  const int groups = static_cast<int>(levels.size());
  const auto df = static_cast<double>(error.error_df);
  const double q = studentizedRangeQuantile(confidence, groups, df);
  std::vector<TukeyComparison> out;
  for (std::size_t i = 0; i < levels.size(); ++i) {
    for (std::size_t j = i + 1; j < levels.size(); ++j) {
      TukeyComparison c;
      c.level = levels[j];
      c.other_level = levels[i];
      c.comparison = c.level + "-" + c.other_level;
      c.diff = means[j] - means[i];
      const double se = std::sqrt((error.error_mean_sq / 2.0) * (1.0 / counts[i] + 1.0 / counts[j]));
      c.lower = c.diff - q * se;
      c.upper = c.diff + q * se;
      // No error variance (or none estimable): a difference is certain, no difference says
      // nothing (NaN, as R's ptukey gives), rather than a failed analysis.
      const double statistic = std::abs(c.diff) / se;
      c.p_adjusted = std::isnan(statistic)   ? std::numeric_limits<double>::quiet_NaN()
                     : std::isinf(statistic) ? 0.0
                                             : studentizedRangeUpperTail(statistic, groups, df);
      out.push_back(std::move(c));
    }
  }
  return out;
}

}  // namespace

TukeyResult tukeyHsd(const TwoWayData& data, Factor factor, const AnovaOptions& options,
                     double confidence) {
  HATTR_THROW_UNLESS(confidence > 0.0 && confidence < 1.0,
                     "tukeyHsd: confidence: expected a level in (0, 1), got {}", confidence);
  const BalancedFit fit = fitBalanced("tukeyHsd", data);
  const AnovaTable table = tableOf(data, fit, options);
  const bool by_a = factor == Factor::kA;
  const AnovaRow& effect = table.rows[by_a ? 0 : 1];
  const AnovaRow& error = table.row(effect.error_term);
  HATTR_THROW_UNLESS(error.df >= 2,
                     "tukeyHsd: error term {} has {} degree(s) of freedom: expected at least 2",
                     error.source, error.df);

  TukeyResult result;
  result.factor = effect.source;
  result.confidence = confidence;
  result.error_term = error.source;
  result.error_mean_sq = error.mean_sq;
  result.error_df = error.df;

  // Level means, each over (other factor's levels x replicates) observations.
  const std::vector<std::string>& levels = by_a ? fit.a.levels : fit.b.levels;
  const double per_level =
      static_cast<double>((by_a ? fit.b.levels.size() : fit.a.levels.size()) * fit.replicates);
  result.comparisons = tukeyComparisons(levels, by_a ? fit.a_mean : fit.b_mean,
                                        std::vector<double>(levels.size(), per_level), result, confidence);
  return result;
}

Descriptive describe(std::span<const double> values) {
  HATTR_THROW_UNLESS(!values.empty(), "describe: expected at least 1 value, got 0");
  for (std::size_t i = 0; i < values.size(); ++i) {
    HATTR_THROW_UNLESS(std::isfinite(values[i]),
                       "describe: value {}: expected a finite number, got {}", i, values[i]);
  }
  return describeUnchecked(values);
}

std::vector<GroupStats> describeGroups(const TwoWayData& data, Grouping grouping) {
  checkColumns("describeGroups", data);
  const LevelIndex a = indexLevels(data.a);
  const LevelIndex b = indexLevels(data.b);
  // Group key: A level, B level or cell (A major).
  const std::size_t nb = b.levels.size();
  const std::size_t groups = grouping == Grouping::kA   ? a.levels.size()
                             : grouping == Grouping::kB ? nb
                                                        : a.levels.size() * nb;
  std::vector<std::vector<double>> values(groups);
  for (std::size_t r = 0; r < data.y.size(); ++r) {
    const std::size_t key = grouping == Grouping::kA   ? a.of_row[r]
                            : grouping == Grouping::kB ? b.of_row[r]
                                                       : a.of_row[r] * nb + b.of_row[r];
    values[key].push_back(data.y[r]);
  }
  std::vector<GroupStats> stats;
  for (std::size_t g = 0; g < groups; ++g) {
    if (values[g].empty()) continue;  // a cell without observations
    GroupStats s;
    if (grouping == Grouping::kA) s.a_level = a.levels[g];
    if (grouping == Grouping::kB) s.b_level = b.levels[g];
    if (grouping == Grouping::kCells) {
      s.a_level = a.levels[g / nb];
      s.b_level = b.levels[g % nb];
    }
    s.stats = describeUnchecked(values[g]);
    stats.push_back(std::move(s));
  }
  return stats;
}

std::vector<LevelVariance> interSubjectVariance(const TwoWayData& data) {
  const std::vector<GroupStats> cells = describeGroups(data, Grouping::kCells);
  std::vector<LevelVariance> result;
  for (const auto& level : indexLevels(data.a).levels) {
    std::vector<double> subject_means;
    for (const auto& cell : cells) {
      if (cell.a_level == level) subject_means.push_back(cell.stats.mean);
    }
    result.push_back({level, describeUnchecked(subject_means).variance});
  }
  return result;
}

namespace {

/// One-way fit: the levels, each group's count and mean, and the sums of squares.
struct OneWayFit {
  LevelIndex levels;
  std::vector<double> count, mean;
  double ss_between = 0.0, ss_within = 0.0;
  std::size_t df_between = 0, df_within = 0;
};

OneWayFit fitOneWay(std::string_view function, const OneWayData& data) {
  HATTR_THROW_UNLESS(data.group.size() == data.y.size(),
                     "{}: columns differ in length: expected equal lengths, got {} ({}) and {} (response)", function,
                     data.group.size(), data.factor, data.y.size());
  for (std::size_t r = 0; r < data.y.size(); ++r) {
    HATTR_THROW_UNLESS(std::isfinite(data.y[r]), "{}: row {}: response: expected a finite number, got {}", function, r,
                       data.y[r]);
    HATTR_THROW_UNLESS(!data.group[r].empty(), "{}: row {}: {}: expected a level name, got \"\"", function, r,
                       data.factor);
  }
  OneWayFit fit;
  fit.levels = indexLevels(data.group);
  const std::size_t k = fit.levels.levels.size();
  HATTR_THROW_UNLESS(k >= 2, "{}: {}: expected at least 2 levels, got {}", function, data.factor, k);
  HATTR_THROW_UNLESS(data.y.size() > k, "{}: expected more observations than the {} levels of {}, got {}", function, k,
                     data.factor, data.y.size());
  fit.count.assign(k, 0.0);
  fit.mean.assign(k, 0.0);
  double grand = 0.0;
  for (std::size_t r = 0; r < data.y.size(); ++r) {
    fit.count[fit.levels.of_row[r]] += 1.0;
    fit.mean[fit.levels.of_row[r]] += data.y[r];
    grand += data.y[r];
  }
  grand /= static_cast<double>(data.y.size());
  for (std::size_t g = 0; g < k; ++g) {
    fit.mean[g] /= fit.count[g];
    fit.ss_between += fit.count[g] * (fit.mean[g] - grand) * (fit.mean[g] - grand);
  }
  for (std::size_t r = 0; r < data.y.size(); ++r) {
    const double e = data.y[r] - fit.mean[fit.levels.of_row[r]];
    fit.ss_within += e * e;
  }
  fit.df_between = k - 1;
  fit.df_within = data.y.size() - k;
  return fit;
}

}  // namespace

AnovaTable oneWayAnova(const OneWayData& data) {
  const OneWayFit fit = fitOneWay("oneWayAnova", data);
  AnovaRow residuals{std::string(kResiduals), fit.df_within, fit.ss_within,
                     fit.ss_within / static_cast<double>(fit.df_within), kNaN, kNaN, kNaN, ""};
  AnovaTable table;
  table.rows = {effectRow(data.factor, fit.df_between, fit.ss_between, residuals), residuals};
  table.replicates = 0;
  table.a_levels = fit.levels.levels;
  return table;
}

TukeyResult tukeyHsdOneWay(const OneWayData& data, double confidence) {
  HATTR_THROW_UNLESS(confidence > 0.0 && confidence < 1.0,
                     "tukeyHsdOneWay: confidence: expected a level in (0, 1), got {}", confidence);
  const OneWayFit fit = fitOneWay("tukeyHsdOneWay", data);
  HATTR_THROW_UNLESS(fit.df_within >= 2, "tukeyHsdOneWay: Residuals has {} degree(s) of freedom: expected at least 2",
                     fit.df_within);
  TukeyResult result;
  result.factor = data.factor;
  result.confidence = confidence;
  result.error_term = std::string(kResiduals);
  result.error_mean_sq = fit.ss_within / static_cast<double>(fit.df_within);
  result.error_df = fit.df_within;
  result.comparisons = tukeyComparisons(fit.levels.levels, fit.mean, fit.count, result, confidence);
  return result;
}

}  // namespace hattr::analysis
