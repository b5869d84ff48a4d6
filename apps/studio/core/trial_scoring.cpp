#include "core/trial_scoring.hpp"

#include <fmt/format.h>

namespace hattr::studio {

analysis::TrialScore scoreTrial(const HapticProfile& expert, const HapticProfile& trial) {
  return analysis::TrialScorer(expert).score(trial);
}

std::string describeScores(const analysis::TrialScore& s) {
  return fmt::format("shape {:.4g} (x {:.4g}, y {:.4g}) · height {:.4g} · force {:.4g} (fx {:.4g}, fy {:.4g}, fz {:.4g})",
                     s.shape(), s.x, s.y, s.z, s.force(), s.fx, s.fy, s.fz);
}

}  // namespace hattr::studio
