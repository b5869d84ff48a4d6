#pragma once
/// Dynamic time warping (DTW), the paper's measure of how far a trainee's trace is from
/// the expert's (section 5.1.2). Series are plain doubles in whatever unit the caller
/// chose (usually normalized, see preprocess.hpp); a DTW cost has the unit of the cost
/// function: the series' unit for kAbsolute, its square for kSquared.
///
/// The recurrence is the classic one, over 0-based indices:
///   D(i, j) = cost(a[i], b[j]) + min(D(i-1, j), D(i, j-1), D(i-1, j-1)),
///   D(-1, -1) = 0, D(-1, j) = D(i, -1) = +inf,
/// and the DTW cost is D(n-1, m-1). docs/analysis.md gives the options and complexity.
///
/// Every function here is offline analysis code: call it from any thread but the servo
/// thread (it allocates). Functions are thread-safe (no shared state). Bad input
/// (empty series, non-finite values, mismatched channels, a NaN option) throws
/// hattr::InputError.

#include <Eigen/Core>
#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hattr::analysis {

/// The local cost between two samples.
enum class DtwCost {
  kAbsolute,  ///< |x - y|, the paper's metric (default)
  kSquared,   ///< (x - y)^2
};

/// The name of a local cost as files, the CLI and Python spell it: "abs", "sq".
[[nodiscard]] std::string_view dtwCostName(DtwCost cost);
/// The cost with that name; throws InputError listing the names otherwise.
[[nodiscard]] DtwCost parseDtwCost(std::string_view name);

/// Options of every DTW function.
struct DtwOptions {
  /// Local cost between two samples.
  DtwCost cost = DtwCost::kAbsolute;
  /// Sakoe–Chiba band as a fraction of the longer series: cells with |i - j| > r are
  /// excluded, r = max(ceil(band_fraction * max(n, m)), |n - m|). A negative value or a
  /// value >= 1 means no band. NaN is refused.
  double band_fraction = -1.0;
  /// Early abandoning: any result above this bound is returned as +infinity, and the
  /// computation stops as soon as no warping path can stay at or below it. NaN is refused.
  double abandon_above = std::numeric_limits<double>::infinity();
  /// Return the warping path as well as the cost (dtw() and dtwDependent() only; costs
  /// O(n * band) memory instead of O(band)).
  bool want_path = false;
};

/// One cell (i, j) of a warping path: a[i] is matched with b[j].
struct WarpStep {
  std::size_t i = 0;
  std::size_t j = 0;
  friend bool operator==(const WarpStep&, const WarpStep&) = default;
};

/// A DTW cost and, if asked for, its warping path from (0, 0) to (n-1, m-1). When the
/// cost is +infinity (abandoned), the path is empty.
struct DtwResult {
  double cost = 0.0;
  std::vector<WarpStep> path;
};

/// Means "no band" where a band radius is expected.
inline constexpr std::size_t kNoBand = std::numeric_limits<std::size_t>::max();

/// The Sakoe–Chiba band radius r for series of lengths n and m (see
/// DtwOptions::band_fraction), or kNoBand when the band does not restrict anything.
/// Throws InputError if band_fraction is NaN.
[[nodiscard]] std::size_t dtwBandRadius(std::size_t n, std::size_t m, double band_fraction);

/// DTW cost of two univariate series, and the warping path if options.want_path.
/// Without a path it runs the vectorized kernel in O(band) memory; with a path it keeps
/// the banded cost matrix. Throws InputError on an empty series, a non-finite value or a
/// NaN option.
[[nodiscard]] DtwResult dtw(std::span<const double> a, std::span<const double> b,
                            const DtwOptions& options = {});

/// DTW cost only (options.want_path is ignored): the fast path, O((n + m) * band) time,
/// O(band) memory, SIMD over anti-diagonals. Throws as dtw().
[[nodiscard]] double dtwDistance(std::span<const double> a, std::span<const double> b,
                                 const DtwOptions& options = {});

/// The plain full-matrix DTW, (n+1) x (m+1) doubles, written for clarity: the
/// baseline of tests and benchmarks. Honours options.cost and options.band_fraction;
/// ignores abandon_above and want_path. Throws as dtw().
[[nodiscard]] double dtwReference(std::span<const double> a, std::span<const double> b,
                                  const DtwOptions& options = {});

/// A multivariate series: one std::vector per channel (x, y, force, ...), all channels of
/// one series of equal length.
using Channels = std::span<const std::vector<double>>;

/// Dependent multivariate DTW: one common warping path; a cell's cost is the sum over
/// channels of the per-channel cost. Both series need the same number of channels (>= 1).
/// Honours every option. Throws InputError on mismatched channel counts or lengths, and
/// as dtw().
[[nodiscard]] DtwResult dtwDependent(Channels a, Channels b, const DtwOptions& options = {});

/// dtwDependent() by the plain full-matrix method (the test baseline). Honours cost and
/// band only. Throws as dtwDependent().
[[nodiscard]] double dtwDependentReference(Channels a, Channels b, const DtwOptions& options = {});

/// Independent multivariate DTW: a separate DTW (own path) per channel; returns the cost
/// of each channel in channel order. abandon_above applies to each channel on its own;
/// want_path is ignored. Throws as dtwDependent().
[[nodiscard]] std::vector<double> dtwIndependent(Channels a, Channels b,
                                                 const DtwOptions& options = {});

/// The sum over channels of the independent per-channel DTW costs. abandon_above applies
/// to the sum: the result is +infinity when the sum exceeds it, and later channels are
/// abandoned against what remains of the bound. Throws as dtwDependent().
[[nodiscard]] double dtwIndependentSum(Channels a, Channels b, const DtwOptions& options = {});

/// DTW costs of many pairs at once: result[p] = dtwDistance(a[p], b[p], options). When all
/// a[p] share one length and all b[p] another, SIMD lanes run different pairs (the
/// fastest way to compute many costs); otherwise each pair runs on its own. Up to `threads`
/// (>= 1) threads, never more than the hardware runs at once, share the pairs in whole SIMD
/// blocks, so the costs are the same to the bit for any number of threads. want_path is
/// ignored. Throws InputError if a and b differ in size, if threads == 0, and as dtw().
[[nodiscard]] std::vector<double> dtwBatch(std::span<const std::vector<double>> a,
                                           std::span<const std::vector<double>> b,
                                           const DtwOptions& options = {}, unsigned threads = 1);
/// The same over series the caller owns (NumPy arrays from Python): read in place, not copied.
[[nodiscard]] std::vector<double> dtwBatch(std::span<const std::span<const double>> a,
                                           std::span<const std::span<const double>> b,
                                           const DtwOptions& options = {}, unsigned threads = 1);

/// The symmetric matrix of DTW costs between every two of `series`, with a zero
/// diagonal; entry (i, j) = dtwDistance(series[i], series[j], options) for i < j.
/// Up to `threads` (>= 1) worker threads share the pairs, never more than the hardware runs at
/// once. want_path is ignored. Throws InputError on a bad series (naming its index) or
/// threads == 0.
[[nodiscard]] Eigen::MatrixXd dtwCostMatrix(std::span<const std::vector<double>> series,
                                            const DtwOptions& options = {}, unsigned threads = 2);

/// The envelope of a series for LB_Keogh: lower[i] and upper[i] are the least and greatest
/// value of series[j] for |i - j| <= radius.
struct DtwEnvelope {
  std::vector<double> lower;
  std::vector<double> upper;
};

/// The envelope of `series` within `radius` samples (kNoBand: the whole series). Throws
/// InputError on an empty series or a non-finite value.
[[nodiscard]] DtwEnvelope dtwEnvelope(std::span<const double> series, std::size_t radius);

/// LB_Keogh (Keogh and Ratanamahatana 2005): a lower bound of the banded DTW cost between a
/// series q and `candidate` of the same length, from q's envelope within the band's radius:
/// the sum over i of cost(candidate[i], the nearest point of [lower[i], upper[i]]). For any
/// candidate, lbKeogh(candidate, dtwEnvelope(q, r), cost) <= dtwDistance(candidate, q) with the
/// band of radius r and the same cost, so a search may skip a candidate whose bound exceeds its
/// best so far without changing its answer. Stops summing once the sum exceeds `abandon_above`
/// (and returns the partial sum, already above it), checked every 16 values. Vectorized (the
/// kernels' instruction set). Throws InputError when the lengths differ.
[[nodiscard]] double lbKeogh(std::span<const double> candidate, const DtwEnvelope& envelope, DtwCost cost,
                             double abandon_above = std::numeric_limits<double>::infinity());

/// LB_Improved (Lemire 2009): LB_Keogh of `candidate` against q's envelope, plus LB_Keogh of q
/// against the envelope (same radius) of the candidate projected onto q's envelope. A tighter
/// lower bound of the same banded DTW cost (either cost), at about three times LB_Keogh's work.
/// Returns as soon as the sum exceeds `abandon_above`. Throws InputError when lengths differ.
[[nodiscard]] double lbImproved(std::span<const double> candidate, std::span<const double> query,
                                const DtwEnvelope& query_envelope, std::size_t radius, DtwCost cost,
                                double abandon_above = std::numeric_limits<double>::infinity());

/// A query's envelope summarised over consecutive segments of `segment` values (the last may be
/// shorter), for a bound cheaper than LB_Keogh: each segment's width and the means of the
/// envelope's lower and upper sides over it. The segments of several channels may follow one
/// another (append), matched by the candidates' means laid out the same way.
struct DtwSegmentEnvelope {
  std::vector<double> lower;
  std::vector<double> upper;
  std::vector<double> width;
  void append(const DtwSegmentEnvelope& other);
};

/// The envelope's segment means. Throws InputError for a segment of 0 or an empty envelope.
[[nodiscard]] DtwSegmentEnvelope dtwSegmentEnvelope(const DtwEnvelope& envelope, std::size_t segment);

/// The means of `series` over the same segments, appended to `out`.
void appendSegmentMeans(std::span<const double> series, std::size_t segment, std::vector<double>& out);

/// LB_Keogh over segments (the absolute cost): for candidate c, whose segment means are
/// means[c·k, (c + 1)·k) with k = envelope.width.size(), out[c] = Σ_s width[s] · the distance
/// of its mean from [lower[s], upper[s]]. In a segment of w values with mean m, a candidate's part
/// of LB_Keogh, Σ max(x − U, 0) + max(L − x, 0), is at least w · (max(m − Ū, 0) + max(L̄ − m, 0)),
/// a sum of positive parts being at least the positive part of the sum: so out[c] is at most
/// lbKeogh (absolute) of the candidate, summed over the appended channels. Vectorized (the
/// kernels' instruction set). An envelope of no segments bounds nothing (0). Throws InputError
/// when `means` is not k values a candidate of `out`, or the envelope's arrays differ in length.
void lbSegmentMeans(std::span<const double> means, const DtwSegmentEnvelope& envelope, std::span<double> out);

/// Pairs the batch kernel computes together on this machine (one SIMD block): a batch of
/// equal-length pairs whose count is a multiple of it leaves no lane idle.
[[nodiscard]] std::size_t dtwBatchWidth();

/// The instruction set the vectorized kernels dispatch to on this machine ("AVX3",
/// "AVX2", "SSE4", ...), for benchmark reports.
[[nodiscard]] std::string dtwSimdTarget();

}  // namespace hattr::analysis
