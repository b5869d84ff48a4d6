// Handwriting kinematics on fixtures whose answers are computed by hand (in the comments),
// with the filter off (cutoff 0) so every measure is exact arithmetic; and the filter's own
// properties: a constant and a line pass unchanged, the cut-off frequency is halved (a
// forward and a backward pass, each −3 dB there), and what it does to a noisy stroke.

#include "hattr/analysis/kinematics.hpp"

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"

namespace hattr::analysis {
namespace {

constexpr KinematicsOptions kRaw{.cutoff_hz = 0.0};

Sample at(double t, double x, double y, bool down, double press_N = 1.5) {
  Sample s;
  s.t_s = t;
  s.p_WT = Vec3(x, y, 0.0);
  s.f_user_W = Vec3(0.0, 0.0, -press_N);
  s.pen_down = down;
  s.in_contact = down;
  return s;
}

HapticProfile profileOf(std::vector<Sample> samples) {
  return HapticProfile::fromSamples({}, {}, std::move(samples), false);
}

// x = 0, 1, 4, 5, 6, 9, 10 (m) at t = 0 … 6 s, pen down throughout. Central differences give
// the speeds 1, 2, 2, 1, 2, 2, 1 (ends one-sided): two peaks (each a plateau of two samples),
// a peak of 2 m/s, a path of 10 m in 6 s.
TEST(Kinematics, SpeedsPeaksAndPathOfAHandComputedStroke) {
  const double xs[] = {0, 1, 4, 5, 6, 9, 10};
  std::vector<Sample> samples;
  for (int i = 0; i < 7; ++i) samples.push_back(at(i, xs[i], 0.0, true));
  const TrialKinematics k = trialKinematics(profileOf(samples), kRaw);
  EXPECT_EQ(k.duration_s, 6.0);
  EXPECT_EQ(k.writing_time_s, 6.0);
  EXPECT_EQ(k.in_air_time_s, 0.0);
  EXPECT_EQ(k.strokes, 1u);
  EXPECT_EQ(k.pen_lifts, 0u);
  EXPECT_EQ(k.path_length_m, 10.0);
  EXPECT_DOUBLE_EQ(k.mean_speed_m_per_s, 10.0 / 6.0);
  EXPECT_EQ(k.peak_speed_m_per_s, 2.0);
  EXPECT_EQ(k.velocity_peaks, 2u);
  EXPECT_TRUE(std::isnan(k.normalized_jerk)) << "7 samples: fewer than the 10 the jerk needs";
}

// x = c t³ sampled every h: three successive central differences give the jerk 6c exactly
// from sample 3 to n − 4, and the jerk, duration and length are taken over that interval:
// T = (n − 7) h, L = c (t₍ₙ₋₄₎³ − t₃³) (a straight, monotonic stroke), ∫|j|² dt = 36 c² T, so
// the normalized jerk is √(½ · 36 c² T · T⁵) / L = √18 · T³ / (t₍ₙ₋₄₎³ − t₃³).
TEST(Kinematics, NormalizedJerkOfACubicIsItsClosedForm) {
  const double c = 0.02;
  const double h = 0.001;
  const int n = 301;
  std::vector<Sample> samples;
  for (int i = 0; i < n; ++i) samples.push_back(at(i * h, c * std::pow(i * h, 3), 0.0, true));
  const TrialKinematics k = trialKinematics(profileOf(samples), kRaw);
  const double t = (n - 1) * h;
  EXPECT_NEAR(k.path_length_m, c * t * t * t, 1e-15);
  const double t3 = 3 * h;
  const double tn4 = (n - 4) * h;
  const double span = tn4 - t3;
  const double expected = std::sqrt(18.0) * span * span * span / (tn4 * tn4 * tn4 - t3 * t3 * t3);
  EXPECT_NEAR(k.normalized_jerk, expected, 1e-6 * expected);
  EXPECT_EQ(k.velocity_peaks, 0u) << "the speed 3ct² only rises";
}

// A stroke sampled slower than twice the cut-off (15 Hz against 10 Hz) is measured raw, not
// refused: a study's trial is never lost to its measurement.
TEST(Kinematics, AStrokeSampledBelowTwiceTheCutOffIsMeasuredRaw) {
  std::vector<Sample> samples;
  for (int i = 0; i < 30; ++i) samples.push_back(at(i / 15.0, 0.001 * i, 0.0, true));
  const TrialKinematics filtered = trialKinematics(profileOf(samples));
  const TrialKinematics raw = trialKinematics(profileOf(samples), kRaw);
  EXPECT_EQ(filtered.path_length_m, raw.path_length_m);
  EXPECT_EQ(filtered.velocity_peaks, raw.velocity_peaks);
}

// Three strokes of 5, 3 and 4 samples (pen down at t = 0…0.4, 1.0…1.2, 2.0…2.3 s), the pen
// up between them; each stroke moves 1 mm a sample along y. Writing time 0.4 + 0.2 + 0.3 =
// 0.9 s; first pen-down 0 s to last 2.3 s is 2.3 s, so 1.4 s in the air; 2 lifts; path
// (4 + 2 + 3) mm = 9 mm. The press is 1.5 N but 2.5 N at one sample: mean (11 × 1.5 + 2.5) / 12.
TEST(Kinematics, StrokesLiftsTimesAndPressOfAHandComputedTrial) {
  std::vector<Sample> samples;
  const auto stroke = [&](double t0, int count) {
    for (int i = 0; i < count; ++i) samples.push_back(at(t0 + 0.1 * i, 0.0, 0.001 * i, true));
  };
  samples.push_back(at(-0.5, 0.0, 0.0, false));  // before the first stroke: not writing
  stroke(0.0, 5);
  samples.push_back(at(0.7, 0.0, 0.0, false));
  stroke(1.0, 3);
  samples.push_back(at(1.5, 0.0, 0.0, false));
  stroke(2.0, 4);
  samples[2].f_user_W.z() = -2.5;
  samples.push_back(at(3.0, 0.0, 0.0, false));
  const TrialKinematics k = trialKinematics(profileOf(samples), kRaw);
  EXPECT_DOUBLE_EQ(k.duration_s, 3.5);
  EXPECT_EQ(k.strokes, 3u);
  EXPECT_EQ(k.pen_lifts, 2u);
  EXPECT_NEAR(k.writing_time_s, 0.9, 1e-12);
  EXPECT_NEAR(k.in_air_time_s, 1.4, 1e-12);
  EXPECT_NEAR(k.path_length_m, 0.009, 1e-15);
  EXPECT_NEAR(k.mean_speed_m_per_s, 0.009 / 0.9, 1e-12);
  EXPECT_NEAR(k.peak_speed_m_per_s, 0.01, 1e-12);
  EXPECT_EQ(k.velocity_peaks, 0u) << "constant speed has no peak";
  EXPECT_DOUBLE_EQ(k.mean_normal_force_N, (11 * 1.5 + 2.5) / 12.0);
  EXPECT_EQ(k.peak_normal_force_N, 2.5);
}

TEST(Kinematics, NothingWrittenGivesZerosAndNoJerk) {
  const TrialKinematics k = trialKinematics(profileOf({at(0, 0, 0, false), at(1, 0.01, 0, false)}));
  EXPECT_EQ(k.duration_s, 1.0);
  EXPECT_EQ(k.strokes, 0u);
  EXPECT_EQ(k.pen_lifts, 0u);
  EXPECT_EQ(k.writing_time_s, 0.0);
  EXPECT_EQ(k.path_length_m, 0.0);
  EXPECT_TRUE(std::isnan(k.normalized_jerk));
  EXPECT_TRUE(toJson(k)["normalized_jerk"].is_null());
  EXPECT_EQ(toJson(k).size(), kinematicsNames().size());
}

// ---- The filter ---------------------------------------------------------------------

TEST(LowPassZeroPhase, PassesAConstantAndALineUnchanged) {
  std::vector<double> constant(200, 0.25);
  std::vector<double> line(200);
  for (std::size_t i = 0; i < line.size(); ++i) line[i] = 0.001 * static_cast<double>(i) - 0.05;
  const std::vector<double> c = lowPassZeroPhase(constant, 10.0, 1000.0);
  const std::vector<double> l = lowPassZeroPhase(line, 10.0, 1000.0);
  for (std::size_t i = 0; i < line.size(); ++i) {
    EXPECT_NEAR(c[i], 0.25, 1e-14) << i;
    EXPECT_NEAR(l[i], line[i], 1e-12) << i;  // each pass starts on the line: no transient
  }
}

TEST(LowPassZeroPhase, HalvesASineAtTheCutOffAndKeepsItsPhase) {
  const double rate = 1000.0;
  const double cutoff = 10.0;
  std::vector<double> x(4000);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::sin(2.0 * std::numbers::pi * cutoff * static_cast<double>(i) / rate);
  const std::vector<double> y = lowPassZeroPhase(x, cutoff, rate);
  // Away from the ends: y = |H|² x, |H|² = ½ at the cut-off, no delay (zero phase).
  for (std::size_t i = 1000; i < 3000; ++i) EXPECT_NEAR(y[i], 0.5 * x[i], 1e-3) << i;
}

TEST(LowPassZeroPhase, RefusesACutOffAtOrAboveNyquist) {
  EXPECT_THROW((void)lowPassZeroPhase(std::vector<double>(50, 0.0), 500.0, 1000.0), InputError);
  EXPECT_THROW((void)lowPassZeroPhase(std::vector<double>(50, 0.0), 0.0, 1000.0), InputError);
  EXPECT_THROW((void)trialKinematics(profileOf({at(0, 0, 0, true)}), {.cutoff_hz = -1.0}), InputError);
}

// Measurement noise of 20 µm on a slow stroke (a half sine of speed, one peak) makes the raw
// speed jagged (many peaks); at 10 Hz the filter leaves the one peak the movement has.
TEST(Kinematics, TheFilterLeavesTheMovementsOwnVelocityPeak) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 20e-6);
  std::vector<Sample> samples;
  for (int i = 0; i <= 500; ++i) {
    const double t = i * 0.001;
    const double x = 0.01 * (t / 0.5 - std::sin(2.0 * std::numbers::pi * t / 0.5) / (2.0 * std::numbers::pi));
    samples.push_back(at(t, x + noise(rng), noise(rng), true));
  }
  const HapticProfile p = profileOf(samples);
  EXPECT_GT(trialKinematics(p, kRaw).velocity_peaks, 20u);
  const TrialKinematics filtered = trialKinematics(p);
  EXPECT_EQ(filtered.velocity_peaks, 1u);
  EXPECT_NEAR(filtered.path_length_m, 0.01, 0.0005);
  EXPECT_NEAR(filtered.peak_speed_m_per_s, 0.04, 0.002);  // 2 × 10 mm / 0.5 s at mid-stroke
}

}  // namespace
}  // namespace hattr::analysis
