#pragma once
// The expert's writing in the network tests: a figure of eight (20 mm wide, 12 mm high) written
// once in `period_s`, pressing 1.2 N, sampled every 10 ms.

#include <cmath>

#include "hattr/analysis/dtw.hpp"
#include "hattr/core/haptic_profile.hpp"

namespace hattr::test {

inline HapticProfile figureEightScript(double period_s) {
  constexpr double kPi = 3.141592653589793;
  HapticProfile p;
  const int n = static_cast<int>(std::lround(period_s * 100.0));
  for (int i = 0; i <= n; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    const double w = 2.0 * kPi / period_s;
    s.p_WT = Vec3(0.02 * std::sin(w * s.t_s), 0.012 * std::sin(2.0 * w * s.t_s), 0.0);
    s.v_WT = Vec3(0.02 * w * std::cos(w * s.t_s), 0.024 * w * std::cos(2.0 * w * s.t_s), 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.2);
    s.pen_down = true;
    p.append(s);
  }
  return p;
}

/// The figure of eight, then the pen lifted 5 mm 0.1 s later (so a trial's end rule ends it).
inline HapticProfile figureEightThenLift(double period_s) {
  HapticProfile p = figureEightScript(period_s);
  Sample lifted = p.samples().back();
  lifted.t_s += 0.1;
  lifted.p_WT.z() = 0.005;
  lifted.v_WT.setZero();
  lifted.f_user_W.setZero();
  lifted.pen_down = false;
  p.append(lifted);
  return p;
}

/// The same writing moved by `offset_W` (a trainee who writes beside the expert).
inline HapticProfile offsetScript(const HapticProfile& script, const Vec3& offset_W) {
  HapticProfile p(script.metadata(), script.rawChannels());
  for (Sample s : script.samples()) {
    s.p_WT += offset_W;
    p.append(s);
  }
  return p;
}

/// How far a recorded pen path is from another: the DTW cost of x plus that of y, per sample of
/// `a` (the mentoring tests' distance between a trainee's and the expert's writing).
inline double trajectoryDtw(const HapticProfile& a, const HapticProfile& b) {
  double sum = 0.0;
  for (const char* axis : {"x", "y"}) sum += analysis::dtwDistance(a.channel(axis), b.channel(axis));
  return sum / static_cast<double>(a.size());
}

}  // namespace hattr::test
