#pragma once
/// The studentized range distribution Q(groups, df): the range of `groups` independent
/// standard normal samples divided by an independent sqrt(chi^2_df / df). Tukey's HSD test
/// (anova.hpp) takes its p-values and confidence bounds from here. Boost 1.74 has no such
/// distribution, so the CDF is computed by numerical integration following Copenhaver &
/// Holland (1988), "Computation of the distribution of the maximum studentized range
/// statistic with application to multiple significance testing of simple effects",
/// J. Statist. Comput. Simul. 30:1-15 — the algorithm R's ptukey() uses, with the same
/// Gauss–Legendre rules and cut-offs, so results agree with R to about 1e-14.
///
/// Dimensionless. Pure functions: thread-safe, any thread but the servo thread.

namespace hattr::analysis {

/// P(Q <= q) for Q ~ studentized range with `groups` means and `df` degrees of freedom.
/// 0 for q <= 0, 1 for q = +infinity. groups >= 2, df >= 2 (df may be +infinity; above
/// 25000 the infinite-df form is used, as R does). Throws InputError on groups < 2,
/// df < 2 or a NaN argument.
[[nodiscard]] double studentizedRangeCdf(double q, int groups, double df);

/// P(Q > q), computed as 1 - studentizedRangeCdf() (as R's ptukey(lower.tail = FALSE)),
/// so values far below 1e-12 carry only absolute accuracy. Throws as studentizedRangeCdf().
[[nodiscard]] double studentizedRangeUpperTail(double q, int groups, double df);

/// The quantile q with P(Q <= q) = p, solved to about 1e-14 relative by bracketing and
/// TOMS 748 root finding on studentizedRangeCdf(). (R's qtukey() stops earlier and can
/// differ from this by up to ~1e-7 relative.) Throws InputError unless 0 < p < 1, and as
/// studentizedRangeCdf().
[[nodiscard]] double studentizedRangeQuantile(double p, int groups, double df);

/// Student's t quantile: the t with P(T <= t) = p for `df` degrees of freedom (R's qt()),
/// for confidence intervals. Throws InputError unless 0 < p < 1 and df > 0.
[[nodiscard]] double studentTQuantile(double p, double df);

}  // namespace hattr::analysis
