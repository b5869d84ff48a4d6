#pragma once
// Checks of the simulated expert that the expert's tests and the letter library's share: its
// script passes through a glyph's via points in writing order, and its recording on the
// simulated pen follows the script.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"

namespace hattr::sim::checks {

/// [first, last] sample indices of each pen-down run.
inline std::vector<std::pair<std::size_t, std::size_t>> penDownRuns(const HapticProfile& p) {
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!p[i].pen_down) continue;
    if (runs.empty() || runs.back().second + 1 != i) runs.emplace_back(i, i);
    runs.back().second = i;
  }
  return runs;
}

/// One pen-down run per stroke, passing within 0.05 mm of each via point in writing order.
inline void expectPassesEveryViaPointInOrder(const Glyph& glyph, const HapticProfile& script) {
  const auto runs = penDownRuns(script);
  ASSERT_EQ(runs.size(), glyph.strokes.size());
  for (std::size_t s = 0; s < runs.size(); ++s) {
    std::size_t previous = runs[s].first;
    for (std::size_t k = 0; k < glyph.strokes[s].points.size(); ++k) {
      const Vec2& via = glyph.strokes[s].points[k];
      // The first pen-down sample of this stroke within 0.05 mm of the via point, from where the
      // previous one was passed on (a stroke may come back to a point: a retraced stem, a closed
      // bowl). At 1 kHz and at most 0.1 m/s, a sample lies within 0.05 mm of any point passed.
      std::size_t passed = runs[s].second + 1;
      for (std::size_t i = previous; i <= runs[s].second && passed > runs[s].second; ++i) {
        if ((script[i].p_WT.head<2>() - via).norm() < 5e-5) passed = i;
      }
      EXPECT_LE(passed, runs[s].second) << "stroke " << s + 1 << ", via point " << k + 1
                                        << " is not passed within 0.05 mm after the one before";
      previous = std::min(passed, runs[s].second);
    }
  }
}

/// Where the script writes at its plateau force (more than `min_samples` samples), the recorded
/// pen is on the paper, within 1.5 mm RMS of the script's path (the hand's impedance lags a
/// little), pressing within 10 % of the planned normal force.
inline void expectRecordingFollowsScript(const HapticProfile& script, const HapticProfile& expert,
                                         std::size_t min_samples) {
  const double plateau_N = ExpertConfig{}.axial_force_N * std::sin(ExpertConfig{}.altitude_rad);
  double squared = 0.0, normal = 0.0;
  std::size_t n = 0, in_contact = 0;
  for (std::size_t i = 0; i < std::min(script.size(), expert.size()); ++i) {
    if (!script[i].pen_down || -script[i].f_user_W.z() < plateau_N - 1e-9) continue;
    squared += (expert[i].p_WT.head<2>() - script[i].p_WT.head<2>()).squaredNorm();
    normal += -expert[i].f_user_W.z();
    in_contact += expert[i].in_contact ? 1 : 0;
    ++n;
  }
  ASSERT_GT(n, min_samples);
  EXPECT_EQ(in_contact, n);
  EXPECT_LT(std::sqrt(squared / static_cast<double>(n)), 0.0015);
  EXPECT_NEAR(normal / static_cast<double>(n), plateau_N, 0.1 * plateau_N);
}

}  // namespace hattr::sim::checks
