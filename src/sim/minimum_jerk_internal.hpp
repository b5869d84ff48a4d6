#pragma once
/// The minimum-jerk path through via points (Flash & Hogan 1985): for given times at the
/// via points, the planar path that starts and ends at rest (zero velocity and acceleration)
/// and minimizes the integral of the squared jerk is a quintic polynomial between via points
/// with position, velocity, acceleration, jerk and snap continuous at each via point (the
/// Euler–Lagrange condition x⁽⁶⁾ = 0 with free derivatives at the via points). The via times
/// themselves are chosen, as in Flash & Hogan's via-point solution, to minimize the same cost
/// for a fixed total duration.

#include <optional>
#include <vector>

#include <Eigen/Core>

namespace hattr::sim::detail {

using Vec2 = Eigen::Vector2d;

class MinimumJerkSpline {
 public:
  /// The path through `points` (at least two, no two consecutive equal) reaching point i at
  /// `times[i]` (strictly increasing, times[0] = 0), at rest at both ends. Throws
  /// InvariantError for a singular system (it cannot be for valid input).
  MinimumJerkSpline(std::vector<Vec2> points, std::vector<double> times);

  /// The same path with the via times that minimize the squared jerk for total duration
  /// `duration` (quasi-Newton descent over the time gaps, from gaps proportional to the chord
  /// lengths; no gap below 2 % of the mean).
  static MinimumJerkSpline withOptimalTimes(const std::vector<Vec2>& points, double duration);

  [[nodiscard]] double duration() const noexcept { return times_.back(); }
  [[nodiscard]] const std::vector<double>& times() const noexcept { return times_; }
  /// Position, velocity and acceleration at time t (clamped to [0, duration]).
  [[nodiscard]] Vec2 position(double t) const noexcept { return derivative(t, 0); }
  [[nodiscard]] Vec2 velocity(double t) const noexcept { return derivative(t, 1); }
  [[nodiscard]] Vec2 acceleration(double t) const noexcept { return derivative(t, 2); }
  /// ∫ |jerk|² dt over the whole path.
  [[nodiscard]] double jerkCost() const noexcept;

 private:
  explicit MinimumJerkSpline(std::vector<double> times);
  /// The path, or nullopt if the system is numerically singular for these times.
  static std::optional<MinimumJerkSpline> tryFit(const std::vector<Vec2>& points, std::vector<double> times);
  /// Solves for the coefficients; false if the system is singular.
  bool solve(const std::vector<Vec2>& points);
  [[nodiscard]] Vec2 derivative(double t, int order) const noexcept;

  std::vector<double> times_;
  /// Per segment, the coefficients of x(s) = Σ a_k s^k in the segment's normalized time
  /// s = (t − t_i) / h_i ∈ [0, 1]; column 0 is x, column 1 is y.
  std::vector<Eigen::Matrix<double, 6, 2>> coefficients_;
};

/// The minimum-jerk rest-to-rest blend 10s³ − 15s⁴ + 6s⁵ and its first derivative, for
/// s ∈ [0, 1] (clamped outside).
double minimumJerkBlend(double s) noexcept;
double minimumJerkBlendRate(double s) noexcept;

}  // namespace hattr::sim::detail
