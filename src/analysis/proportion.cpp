#include "hattr/analysis/proportion.hpp"

#include <boost/math/special_functions/beta.hpp>

#include "hattr/core/error.hpp"

namespace hattr::analysis {

Proportion clopperPearson(int successes, int trials, double confidence) {
  HATTR_THROW_UNLESS(trials >= 1, "proportion: expected at least 1 trial, got {}", trials);
  HATTR_THROW_UNLESS(successes >= 0 && successes <= trials, "proportion: expected 0 to {} successes, got {}", trials,
                     successes);
  HATTR_THROW_UNLESS(confidence > 0.0 && confidence < 1.0, "proportion: expected a confidence in (0, 1), got {}",
                     confidence);
  const double tail = (1.0 - confidence) / 2.0;
  const double k = successes;
  const double n = trials;
  Proportion p{successes, trials, k / n, 0.0, 1.0};
  // The interval's ends are quantiles of beta distributions (the binomial's exact bounds).
  if (successes > 0) p.lower = boost::math::ibeta_inv(k, n - k + 1.0, tail);
  if (successes < trials) p.upper = boost::math::ibeta_inv(k + 1.0, n - k, 1.0 - tail);
  return p;
}

}  // namespace hattr::analysis
