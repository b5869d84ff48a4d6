#pragma once
/// A proportion estimated from counts, with its exact (Clopper–Pearson) confidence interval:
/// the power of a design is the fraction of simulated studies that found the effect.

namespace hattr::analysis {

struct Proportion {
  int successes = 0;
  int trials = 0;
  double estimate = 0.0;  ///< successes / trials
  double lower = 0.0;     ///< Clopper–Pearson interval, as R's binom.test
  double upper = 1.0;
};

/// `successes` of `trials` with its two-sided Clopper–Pearson interval at `confidence`.
/// Throws InputError unless 0 <= successes <= trials, trials >= 1 and 0 < confidence < 1.
[[nodiscard]] Proportion clopperPearson(int successes, int trials, double confidence = 0.95);

}  // namespace hattr::analysis
