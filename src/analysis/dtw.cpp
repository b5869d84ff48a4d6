// DTW: input checks, band radius, warping paths, the plain reference, multivariate
// variants and the threaded cost matrix. The vectorized kernels are in dtw_simd.cpp.

#include "hattr/analysis/dtw.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <string_view>
#include <thread>
#include <tuple>
#include <utility>

#include "dtw_internal.hpp"
#include "parallel.hpp"
#include "hattr/core/error.hpp"

namespace hattr::analysis {

std::string_view dtwCostName(DtwCost cost) { return cost == DtwCost::kSquared ? "sq" : "abs"; }

DtwCost parseDtwCost(std::string_view name) {
  if (name == "abs") return DtwCost::kAbsolute;
  if (name == "sq") return DtwCost::kSquared;
  throw InputError(fmt::format("DTW cost \"{}\": expected abs or sq", name));
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The local cost, the same arithmetic as the SIMD kernels.
double localCost(DtwCost cost, double x, double y) {
  const double diff = x - y;
  return cost == DtwCost::kAbsolute ? std::abs(diff) : diff * diff;
}

// A series' name for messages, "a", "a[3]", "b channel 1" or "2", formatted only when a check
// fails (batches check millions of series).
struct SeriesName {
  std::string_view name;
  std::size_t index = kUnindexed;
  std::string_view separator = "";  // before the index; "[" encloses it
  static constexpr std::size_t kUnindexed = static_cast<std::size_t>(-1);
};

}  // namespace
}  // namespace hattr::analysis

template <>
struct fmt::formatter<hattr::analysis::SeriesName> : fmt::formatter<std::string_view> {
  auto format(const hattr::analysis::SeriesName& n, fmt::format_context& ctx) const {
    if (n.index == hattr::analysis::SeriesName::kUnindexed) return fmt::format_to(ctx.out(), "{}", n.name);
    if (n.separator == "[") return fmt::format_to(ctx.out(), "{}[{}]", n.name, n.index);
    return fmt::format_to(ctx.out(), "{}{}{}", n.name, n.separator, n.index);
  }
};

namespace hattr::analysis {
namespace {

// A series must be non-empty and finite; `what` names the series in `function`'s messages.
void checkSeries(std::string_view function, SeriesName what, std::span<const double> s) {
  HATTR_THROW_UNLESS(!s.empty(), "{}: series {} is empty: expected at least 1 value, got 0",
                     function, what);
  const auto bad = std::find_if(s.begin(), s.end(), [](double x) { return !std::isfinite(x); });
  HATTR_THROW_UNLESS(bad == s.end(), "{}: series {} at index {}: expected a finite number, got {}",
                     function, what, bad - s.begin(), *bad);
}

void checkOptions(std::string_view function, const DtwOptions& options) {
  HATTR_THROW_UNLESS(!std::isnan(options.band_fraction),
                     "{}: band_fraction: expected a number (negative or >= 1 for no band), got NaN",
                     function);
  HATTR_THROW_UNLESS(!std::isnan(options.abandon_above),
                     "{}: abandon_above: expected a number or +infinity, got NaN", function);
}

// Both multivariate series: >= 1 channel, the same channel count, equal-length channels.
void checkChannels(std::string_view function, Channels a, Channels b) {
  HATTR_THROW_UNLESS(!a.empty() && !b.empty(),
                     "{}: expected at least 1 channel per series, got {} and {}", function,
                     a.size(), b.size());
  HATTR_THROW_UNLESS(a.size() == b.size(),
                     "{}: expected the same number of channels in both series, got {} and {}",
                     function, a.size(), b.size());
  for (const auto& [series, name] : {std::pair{a, "a"}, std::pair{b, "b"}}) {
    for (std::size_t c = 0; c < series.size(); ++c) {
      checkSeries(function, {name, c, " channel "}, series[c]);
      HATTR_THROW_UNLESS(series[c].size() == series[0].size(),
                         "{}: series {} channel {}: expected {} values like channel 0, got {}",
                         function, name, c, series[0].size(), series[c].size());
    }
  }
}

// Plain full-matrix DTW: D is (n+1) x (m+1) with a border of +inf and D[0][0] = 0.
template <class CellCost>
double fullMatrixDtw(std::size_t n, std::size_t m, std::size_t radius, CellCost cell_cost) {
  const std::size_t cols = m + 1;
  std::vector<double> d((n + 1) * cols, kInf);
  d[0] = 0.0;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t gap = i > j ? i - j : j - i;
      if (radius != kNoBand && gap > radius) continue;
      const double best =
          std::min({d[(i - 1) * cols + j], d[i * cols + j - 1], d[(i - 1) * cols + j - 1]});
      d[i * cols + j] = cell_cost(i - 1, j - 1) + best;
    }
  }
  return d[n * cols + m];
}

// DTW with its warping path: keeps the banded cost matrix (row i holds columns
// [lo(i), hi(i)]), abandons when a whole row exceeds `bound`, then walks back from
// (n-1, m-1) through the smallest predecessor (ties: diagonal, then up, then left).
template <class CellCost>
DtwResult pathDtw(std::size_t n, std::size_t m, std::size_t radius, double bound,
                  CellCost cell_cost) {
  const std::size_t r = std::min(radius, std::max(n, m));
  const auto lo = [&](std::size_t i) { return i > r ? i - r : 0; };
  const auto hi = [&](std::size_t i) { return std::min(m - 1, i + r); };
  std::vector<std::size_t> row_start(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) row_start[i + 1] = row_start[i] + (hi(i) - lo(i) + 1);
  std::vector<double> cells(row_start[n]);
  // D(i, j) with +inf outside the matrix and the band.
  const auto at = [&](std::size_t i, std::size_t j) {
    if (j < lo(i) || j > hi(i)) return kInf;
    return cells[row_start[i] + (j - lo(i))];
  };

  for (std::size_t i = 0; i < n; ++i) {
    double row_min = kInf;
    for (std::size_t j = lo(i); j <= hi(i); ++j) {
      double best = 0.0;
      if (i > 0 || j > 0) {
        const double up = i > 0 ? at(i - 1, j) : kInf;
        const double left = j > 0 ? at(i, j - 1) : kInf;
        const double diag = i > 0 && j > 0 ? at(i - 1, j - 1) : kInf;
        best = std::min({up, left, diag});
      }
      const double value = cell_cost(i, j) + best;
      cells[row_start[i] + (j - lo(i))] = value;
      row_min = std::min(row_min, value);
    }
    if (row_min > bound) return {kInf, {}};
  }
  DtwResult result{at(n - 1, m - 1), {}};
  if (result.cost > bound) return {kInf, {}};

  std::size_t i = n - 1;
  std::size_t j = m - 1;
  result.path.push_back({i, j});
  while (i > 0 || j > 0) {
    const double diag = i > 0 && j > 0 ? at(i - 1, j - 1) : kInf;
    const double up = i > 0 ? at(i - 1, j) : kInf;
    const double left = j > 0 ? at(i, j - 1) : kInf;
    if (diag <= up && diag <= left) {
      --i;
      --j;
    } else if (up <= left) {
      --i;
    } else {
      --j;
    }
    result.path.push_back({i, j});
  }
  std::reverse(result.path.begin(), result.path.end());
  return result;
}

// The kernel problem for channels a[c], b[c] (pointers into the callers' vectors).
struct PreparedPair {
  std::vector<const double*> a;
  std::vector<const double*> b;
  detail::KernelProblem problem;
};

PreparedPair preparePair(Channels a, Channels b, const DtwOptions& options) {
  PreparedPair prepared;
  for (const auto& channel : a) prepared.a.push_back(channel.data());
  for (const auto& channel : b) prepared.b.push_back(channel.data());
  prepared.problem.a = prepared.a.data();
  prepared.problem.b = prepared.b.data();
  prepared.problem.count = a.size();
  prepared.problem.n = a[0].size();
  prepared.problem.m = b[0].size();
  prepared.problem.radius = dtwBandRadius(a[0].size(), b[0].size(), options.band_fraction);
  prepared.problem.cost = options.cost;
  prepared.problem.bound = options.abandon_above;
  return prepared;
}

// Kernel problem for one univariate pair.
detail::KernelProblem univariateProblem(const double* const* a, const double* const* b,
                                        std::size_t n, std::size_t m, const DtwOptions& options) {
  detail::KernelProblem problem;
  problem.a = a;
  problem.b = b;
  problem.count = 1;
  problem.n = n;
  problem.m = m;
  problem.radius = dtwBandRadius(n, m, options.band_fraction);
  problem.cost = options.cost;
  problem.bound = options.abandon_above;
  return problem;
}

// Costs of the checked pairs (a[p], b[p]) into out[p]. When all lengths agree, whole
// blocks of pairs go to the lane-batched kernel; a last partial block goes there too if
// it fills at least half the lanes, else its pairs run one by one, as do pairs of
// differing lengths and, without `lanes_allowed`, every pair.
void costsOfPairs(std::span<const double* const> a, std::span<const double* const> b,
                  std::span<const std::size_t> a_len, std::span<const std::size_t> b_len,
                  const DtwOptions& options, double* out, bool lanes_allowed = true) {
  const std::size_t count = a.size();
  const bool equal_lengths =
      lanes_allowed &&
      std::all_of(a_len.begin(), a_len.end(), [&](std::size_t n) { return n == a_len[0]; }) &&
      std::all_of(b_len.begin(), b_len.end(), [&](std::size_t m) { return m == b_len[0]; });
  std::size_t batched = 0;
  if (equal_lengths) {
    const std::size_t width = detail::batchWidth();
    batched = count % width >= width / 2 ? count : count - count % width;
  }
  if (batched > 0) {
    detail::KernelProblem problem =
        univariateProblem(a.data(), b.data(), a_len[0], b_len[0], options);
    problem.count = batched;
    detail::batchDtw(problem, out);
  }
  for (std::size_t p = batched; p < count; ++p) {
    out[p] = detail::diagonalDtw(univariateProblem(&a[p], &b[p], a_len[p], b_len[p], options));
  }
}

}  // namespace

std::size_t dtwBandRadius(std::size_t n, std::size_t m, double band_fraction) {
  HATTR_THROW_UNLESS(!std::isnan(band_fraction),
                     "dtwBandRadius: band_fraction: expected a number (negative or >= 1 for no "
                     "band), got NaN");
  if (band_fraction < 0.0 || band_fraction >= 1.0) return kNoBand;
  const std::size_t longer = std::max(n, m);
  const auto from_fraction =
      static_cast<std::size_t>(std::ceil(band_fraction * static_cast<double>(longer)));
  const std::size_t radius = std::max(from_fraction, longer - std::min(n, m));
  return radius >= longer ? kNoBand : radius;
}

DtwResult dtw(std::span<const double> a, std::span<const double> b, const DtwOptions& options) {
  if (!options.want_path) return {dtwDistance(a, b, options), {}};
  checkSeries("dtw", {"a"}, a);
  checkSeries("dtw", {"b"}, b);
  checkOptions("dtw", options);
  return pathDtw(a.size(), b.size(), dtwBandRadius(a.size(), b.size(), options.band_fraction),
                 options.abandon_above,
                 [&](std::size_t i, std::size_t j) { return localCost(options.cost, a[i], b[j]); });
}

double dtwDistance(std::span<const double> a, std::span<const double> b,
                   const DtwOptions& options) {
  checkSeries("dtw", {"a"}, a);
  checkSeries("dtw", {"b"}, b);
  checkOptions("dtw", options);
  const double* a_data = a.data();
  const double* b_data = b.data();
  return detail::diagonalDtw(univariateProblem(&a_data, &b_data, a.size(), b.size(), options));
}

double dtwReference(std::span<const double> a, std::span<const double> b,
                    const DtwOptions& options) {
  checkSeries("dtwReference", {"a"}, a);
  checkSeries("dtwReference", {"b"}, b);
  checkOptions("dtwReference", options);
  return fullMatrixDtw(
      a.size(), b.size(), dtwBandRadius(a.size(), b.size(), options.band_fraction),
      [&](std::size_t i, std::size_t j) { return localCost(options.cost, a[i], b[j]); });
}

DtwResult dtwDependent(Channels a, Channels b, const DtwOptions& options) {
  checkChannels("dtwDependent", a, b);
  checkOptions("dtwDependent", options);
  if (!options.want_path) {
    const PreparedPair prepared = preparePair(a, b, options);
    return {detail::diagonalDtw(prepared.problem), {}};
  }
  // Channel costs summed in channel order, as in the kernels.
  return pathDtw(a[0].size(), b[0].size(),
                 dtwBandRadius(a[0].size(), b[0].size(), options.band_fraction),
                 options.abandon_above, [&](std::size_t i, std::size_t j) {
                   double cost = localCost(options.cost, a[0][i], b[0][j]);
                   for (std::size_t c = 1; c < a.size(); ++c) {
                     cost += localCost(options.cost, a[c][i], b[c][j]);
                   }
                   return cost;
                 });
}

double dtwDependentReference(Channels a, Channels b, const DtwOptions& options) {
  checkChannels("dtwDependentReference", a, b);
  checkOptions("dtwDependentReference", options);
  return fullMatrixDtw(a[0].size(), b[0].size(),
                       dtwBandRadius(a[0].size(), b[0].size(), options.band_fraction),
                       [&](std::size_t i, std::size_t j) {
                         double cost = localCost(options.cost, a[0][i], b[0][j]);
                         for (std::size_t c = 1; c < a.size(); ++c) {
                           cost += localCost(options.cost, a[c][i], b[c][j]);
                         }
                         return cost;
                       });
}

std::vector<double> dtwIndependent(Channels a, Channels b, const DtwOptions& options) {
  checkChannels("dtwIndependent", a, b);
  checkOptions("dtwIndependent", options);
  std::vector<double> costs;
  for (std::size_t c = 0; c < a.size(); ++c) {
    const double* a_data = a[c].data();
    const double* b_data = b[c].data();
    costs.push_back(detail::diagonalDtw(
        univariateProblem(&a_data, &b_data, a[c].size(), b[c].size(), options)));
  }
  return costs;
}

double dtwIndependentSum(Channels a, Channels b, const DtwOptions& options) {
  checkChannels("dtwIndependentSum", a, b);
  checkOptions("dtwIndependentSum", options);
  // Each channel is abandoned against what remains of the bound, loosened by a few ulps
  // so that rounding in the subtraction never abandons a sum that would fit; the final
  // comparison is exact.
  double sum = 0.0;
  for (std::size_t c = 0; c < a.size(); ++c) {
    DtwOptions channel_options = options;
    const double remaining = options.abandon_above - sum;
    channel_options.abandon_above = remaining + 1e-12 * std::abs(options.abandon_above);
    const double* a_data = a[c].data();
    const double* b_data = b[c].data();
    const double cost = detail::diagonalDtw(
        univariateProblem(&a_data, &b_data, a[c].size(), b[c].size(), channel_options));
    if (cost == kInf) return kInf;
    sum += cost;
  }
  return sum > options.abandon_above ? kInf : sum;
}

namespace {

/// Pairs [first, last) of `pair_of(p)` = (series a, series b), as the kernel takes them.
struct PairBlock {
  std::vector<const double*> a_ptr, b_ptr;
  std::vector<std::size_t> a_len, b_len;
  template <class PairOf>
  void fill(std::size_t first, std::size_t last, const PairOf& pair_of) {
    a_ptr.clear();
    b_ptr.clear();
    a_len.clear();
    b_len.clear();
    for (std::size_t p = first; p < last; ++p) {
      const auto& [a, b] = pair_of(p);
      a_ptr.push_back(a.data());
      b_ptr.push_back(b.data());
      a_len.push_back(a.size());
      b_len.push_back(b.size());
    }
  }
};

/// dtwBatch over any kind of series (vectors, spans): checked, then shared by the threads.
template <class Series>
std::vector<double> batchCosts(std::span<const Series> a, std::span<const Series> b, const DtwOptions& options,
                               unsigned threads) {
  HATTR_THROW_UNLESS(a.size() == b.size(),
                     "dtwBatch: expected as many series in a as in b, got {} and {}", a.size(),
                     b.size());
  HATTR_THROW_UNLESS(threads >= 1, "dtwBatch: threads: expected at least 1, got {}", threads);
  checkOptions("dtwBatch", options);
  for (std::size_t p = 0; p < a.size(); ++p) {
    checkSeries("dtwBatch", {"a", p, "["}, a[p]);
    checkSeries("dtwBatch", {"b", p, "["}, b[p]);
  }
  // Each thread takes an equal share, a whole number of the kernel's blocks of pairs, so the
  // pairs are blocked as on one thread and the costs are the same to the bit: lanes only when
  // every pair of the batch (not just of a share) has the same lengths.
  const auto same_lengths = [](std::span<const Series> series) {
    return std::all_of(series.begin(), series.end(), [&](const Series& s) { return s.size() == series[0].size(); });
  };
  const bool lanes = same_lengths(a) && same_lengths(b);
  const std::size_t width = detail::batchWidth();
  const std::size_t share = (a.size() + threads - 1) / threads;
  const std::size_t chunk = std::max<std::size_t>(width, (share + width - 1) / width * width);
  std::vector<double> costs(a.size());
  detail::forEachChunk(a.size(), chunk, threads, [&](std::size_t first, std::size_t last) {
    PairBlock block;
    block.fill(first, last, [&](std::size_t p) { return std::tie(a[p], b[p]); });
    costsOfPairs(block.a_ptr, block.b_ptr, block.a_len, block.b_len, options, costs.data() + first, lanes);
  });
  return costs;
}

}  // namespace

std::vector<double> dtwBatch(std::span<const std::vector<double>> a,
                             std::span<const std::vector<double>> b, const DtwOptions& options,
                             unsigned threads) {
  return batchCosts(a, b, options, threads);
}

std::vector<double> dtwBatch(std::span<const std::span<const double>> a, std::span<const std::span<const double>> b,
                             const DtwOptions& options, unsigned threads) {
  return batchCosts(a, b, options, threads);
}

Eigen::MatrixXd dtwCostMatrix(std::span<const std::vector<double>> series,
                              const DtwOptions& options, unsigned threads) {
  HATTR_THROW_UNLESS(threads >= 1, "dtwCostMatrix: threads: expected at least 1, got {}", threads);
  checkOptions("dtwCostMatrix", options);
  for (std::size_t s = 0; s < series.size(); ++s) {
    checkSeries("dtwCostMatrix", {"", s}, series[s]);
  }

  // The pairs i < j, cut into chunks that the workers take in turn.
  const auto count = static_cast<Eigen::Index>(series.size());
  Eigen::MatrixXd costs = Eigen::MatrixXd::Zero(count, count);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < series.size(); ++i) {
    for (std::size_t j = i + 1; j < series.size(); ++j) pairs.emplace_back(i, j);
  }
  detail::forEachChunk(pairs.size(), 64, threads, [&](std::size_t first, std::size_t last) {
    PairBlock block;
    block.fill(first, last, [&](std::size_t p) { return std::tie(series[pairs[p].first], series[pairs[p].second]); });
    std::vector<double> out(last - first);
    costsOfPairs(block.a_ptr, block.b_ptr, block.a_len, block.b_len, options, out.data());
    for (std::size_t p = first; p < last; ++p) {
      const auto i = static_cast<Eigen::Index>(pairs[p].first);
      const auto j = static_cast<Eigen::Index>(pairs[p].second);
      costs(i, j) = out[p - first];
      costs(j, i) = out[p - first];
    }
  });
  return costs;
}

namespace {

/// One side of the envelope, out[i] = best of series over [i - r, i + r] within the series, by
/// van Herk and Gil-Werman's blocks: with blocks of w = 2r + 1 values, `forward` holds each
/// value's best from its block's start and `backward` to its block's end (or the series' end),
/// and a whole window [a, a + 2r] is best(backward[a], forward[a + 2r]). Three passes without
/// branches on the data, whatever the radius.
template <class Best>
void envelopeSide(const double* series, std::size_t n, std::size_t r, double* forward, double* backward, double* out,
                  Best best) {
  const std::size_t w = 2 * r + 1;
  for (std::size_t b = 0; b < n; b += w) {
    const std::size_t e = std::min(n, b + w);
    forward[b] = series[b];
    for (std::size_t i = b + 1; i < e; ++i) forward[i] = best(forward[i - 1], series[i]);
    backward[e - 1] = series[e - 1];
    for (std::size_t i = e - 1; i > b; --i) backward[i - 1] = best(backward[i], series[i - 1]);
  }
  // A window starting in the last block ends at the series' end, inside that block: its
  // backward value alone (the forward one would reach back before the window).
  const std::size_t last_block = ((n - 1) / w) * w;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t last = std::min(n - 1, i + r);  // the window is [i - r, last], from 0 at the start
    if (i < r) out[i] = forward[last];
    else if (i - r >= last_block) out[i] = backward[i - r];
    else out[i] = best(backward[i - r], forward[last]);
  }
}

/// The envelope into `e` (sized to the series), with `scratch` (2n values) for the blocks: no
/// allocation once sized.
void envelopeInto(std::span<const double> series, std::size_t radius, DtwEnvelope& e, std::vector<double>& scratch) {
  const std::size_t n = series.size();
  const std::size_t r = std::min(radius, n);
  e.lower.resize(n);
  e.upper.resize(n);
  scratch.resize(2 * n);
  const auto lower = [](double a, double b) { return std::min(a, b); };
  const auto upper = [](double a, double b) { return std::max(a, b); };
  envelopeSide(series.data(), n, r, scratch.data(), scratch.data() + n, e.lower.data(), lower);
  envelopeSide(series.data(), n, r, scratch.data(), scratch.data() + n, e.upper.data(), upper);
}

}  // namespace

DtwEnvelope dtwEnvelope(std::span<const double> series, std::size_t radius) {
  HATTR_THROW_UNLESS(!series.empty(), "DTW envelope: the series is empty; expected at least one value");
  for (std::size_t i = 0; i < series.size(); ++i) {
    HATTR_THROW_UNLESS(std::isfinite(series[i]), "DTW envelope: value {} is {}; expected a finite number", i, series[i]);
  }
  DtwEnvelope e;
  std::vector<double> scratch;
  envelopeInto(series, radius, e, scratch);
  return e;
}

double lbKeogh(std::span<const double> candidate, const DtwEnvelope& envelope, DtwCost cost, double abandon_above) {
  HATTR_THROW_UNLESS(candidate.size() == envelope.lower.size() && candidate.size() == envelope.upper.size(),
                     "LB_Keogh: the candidate has {} values and the envelope {}; expected the same length",
                     candidate.size(), envelope.lower.size());
  return detail::lbKeoghSimd({.candidate = candidate.data(), .lower = envelope.lower.data(),
                              .upper = envelope.upper.data(), .n = candidate.size(),
                              .squared = cost == DtwCost::kSquared, .abandon_above = abandon_above});
}

void DtwSegmentEnvelope::append(const DtwSegmentEnvelope& other) {
  lower.insert(lower.end(), other.lower.begin(), other.lower.end());
  upper.insert(upper.end(), other.upper.begin(), other.upper.end());
  width.insert(width.end(), other.width.begin(), other.width.end());
}

DtwSegmentEnvelope dtwSegmentEnvelope(const DtwEnvelope& envelope, std::size_t segment) {
  HATTR_THROW_UNLESS(segment >= 1, "DTW segment envelope: segment 0; expected at least 1 value");
  HATTR_THROW_UNLESS(!envelope.lower.empty() && envelope.lower.size() == envelope.upper.size(),
                     "DTW segment envelope: sides of {} and {} values; expected the same, at least 1",
                     envelope.lower.size(), envelope.upper.size());
  DtwSegmentEnvelope e;
  appendSegmentMeans(envelope.lower, segment, e.lower);
  appendSegmentMeans(envelope.upper, segment, e.upper);
  for (std::size_t b = 0; b < envelope.lower.size(); b += segment) {
    e.width.push_back(static_cast<double>(std::min(envelope.lower.size(), b + segment) - b));
  }
  return e;
}

void appendSegmentMeans(std::span<const double> series, std::size_t segment, std::vector<double>& out) {
  HATTR_THROW_UNLESS(segment >= 1, "segment means: segment 0; expected at least 1 value");
  for (std::size_t b = 0; b < series.size(); b += segment) {
    const std::size_t e = std::min(series.size(), b + segment);
    double sum = 0.0;
    for (std::size_t k = b; k < e; ++k) sum += series[k];
    out.push_back(sum / static_cast<double>(e - b));
  }
}

void lbSegmentMeans(std::span<const double> means, const DtwSegmentEnvelope& envelope, std::span<double> out) {
  const std::size_t k = envelope.width.size();
  HATTR_THROW_UNLESS(envelope.lower.size() == k && envelope.upper.size() == k,
                     "segment bound: envelope of {}, {} and {} values; expected the same", envelope.lower.size(),
                     envelope.upper.size(), k);
  HATTR_THROW_UNLESS(means.size() == out.size() * k,
                     "segment bound: {} means for {} candidates; expected {} a candidate", means.size(), out.size(), k);
  if (k == 0) {  // no segments (a feature set of no series): nothing bounds
    std::fill(out.begin(), out.end(), 0.0);
    return;
  }
  detail::segmentBoundsSimd(means.data(), out.size(),
                            {.lower = envelope.lower.data(), .upper = envelope.upper.data(),
                             .width = envelope.width.data(), .size = k},
                            out.data());
}

double lbImproved(std::span<const double> candidate, std::span<const double> query, const DtwEnvelope& query_envelope,
                  std::size_t radius, DtwCost cost, double abandon_above) {
  HATTR_THROW_UNLESS(query.size() == candidate.size(), "LB_Improved: the candidate has {} values and the query {}; "
                                                       "expected the same length",
                     candidate.size(), query.size());
  const double first = lbKeogh(candidate, query_envelope, cost, abandon_above);
  if (first > abandon_above) return first;
  // The candidate projected onto the query's envelope, then the query against its envelope
  // (this thread's buffers, reused: the search calls it for many candidates).
  thread_local std::vector<double> projected;
  thread_local DtwEnvelope envelope;
  thread_local std::vector<double> scratch;
  projected.resize(candidate.size());
  for (std::size_t i = 0; i < candidate.size(); ++i) {
    projected[i] = std::clamp(candidate[i], query_envelope.lower[i], query_envelope.upper[i]);
  }
  envelopeInto(projected, radius, envelope, scratch);
  return first + lbKeogh(query, envelope, cost, abandon_above - first);
}

std::size_t dtwBatchWidth() { return detail::batchWidth(); }

std::string dtwSimdTarget() { return detail::simdTargetName(); }

}  // namespace hattr::analysis
