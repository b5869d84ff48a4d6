#include "core/trial_scoring.hpp"

namespace hattr::studio {

analysis::TrialScore scoreTrial(const HapticProfile& expert, const HapticProfile& trial) {
  return analysis::TrialScorer(expert).score(trial);
}

}  // namespace hattr::studio
