#include "minimum_jerk_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include <Eigen/LU>

#include "hattr/core/error.hpp"

namespace hattr::sim::detail {
namespace {

/// k! / (k − m)!: the factor of s^(k−m) in the m-th derivative of s^k.
double fallingFactorial(int k, int m) {
  double f = 1.0;
  for (int i = 0; i < m; ++i) f *= static_cast<double>(k - i);
  return f;
}

}  // namespace

MinimumJerkSpline::MinimumJerkSpline(std::vector<Vec2> points, std::vector<double> times) : times_(std::move(times)) {
  HATTR_DEMAND(points.size() >= 2 && points.size() == times_.size(), "{} points, {} times", points.size(), times_.size());
  for (std::size_t i = 0; i + 1 < times_.size(); ++i) {
    HATTR_DEMAND(times_[i + 1] > times_[i], "via times must increase: t[{}] = {}, t[{}] = {}", i, times_[i], i + 1,
                 times_[i + 1]);
  }
  HATTR_DEMAND(solve(points), "the minimum-jerk system for {} via points is singular", points.size());
}

bool MinimumJerkSpline::solve(const std::vector<Vec2>& points) {
  const auto n = static_cast<int>(points.size()) - 1;  // segments
  // Unknowns: 6 coefficients per segment, in normalized segment time. Rows: the rest
  // conditions at both ends, and at each inner via point its position from both sides
  // and the continuity of derivatives 1 to 4 (each scaled by h^m to balance the rows).
  const int size = 6 * n;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(size, size);
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(size, 2);
  int row = 0;
  const auto h = [&](int i) { return times_[i + 1] - times_[i]; };
  // Start at rest at points[0].
  a(row, 0) = 1.0;
  b.row(row++) = points[0].transpose();
  a(row++, 1) = 1.0;
  a(row++, 2) = 2.0;
  for (int j = 1; j < n; ++j) {
    const int left = 6 * (j - 1);
    const int right = 6 * j;
    for (int k = 0; k < 6; ++k) a(row, left + k) = 1.0;
    b.row(row++) = points[j].transpose();
    a(row, right) = 1.0;
    b.row(row++) = points[j].transpose();
    const double ratio = h(j - 1) / h(j);
    for (int m = 1; m <= 4; ++m) {
      for (int k = m; k < 6; ++k) a(row, left + k) = fallingFactorial(k, m);
      a(row, right + m) = -fallingFactorial(m, m) * std::pow(ratio, m);
      ++row;
    }
  }
  // End at rest at points[n].
  const int last = 6 * (n - 1);
  for (int k = 0; k < 6; ++k) a(row, last + k) = 1.0;
  b.row(row++) = points[n].transpose();
  for (int k = 1; k < 6; ++k) a(row, last + k) = fallingFactorial(k, 1);
  ++row;
  for (int k = 2; k < 6; ++k) a(row, last + k) = fallingFactorial(k, 2);
  ++row;
  HATTR_DEMAND(row == size, "built {} rows for {} unknowns", row, size);

  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(a);
  const Eigen::MatrixXd x = lu.solve(b);
  if (!x.allFinite() || (a * x - b).norm() > 1e-9 * (1.0 + b.norm())) return false;
  coefficients_.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) coefficients_[static_cast<std::size_t>(i)] = x.block<6, 2>(6 * i, 0);
  return true;
}

MinimumJerkSpline::MinimumJerkSpline(std::vector<double> times) : times_(std::move(times)) {}

std::optional<MinimumJerkSpline> MinimumJerkSpline::tryFit(const std::vector<Vec2>& points, std::vector<double> times) {
  MinimumJerkSpline spline(std::move(times));
  if (!spline.solve(points)) return std::nullopt;
  return spline;
}

Vec2 MinimumJerkSpline::derivative(double t, int order) const noexcept {
  t = std::clamp(t, 0.0, duration());
  const auto upper = std::upper_bound(times_.begin(), times_.end(), t);
  auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(upper - times_.begin() - 1, 0));
  i = std::min(i, coefficients_.size() - 1);
  const double h = times_[i + 1] - times_[i];
  const double s = (t - times_[i]) / h;
  const auto& c = coefficients_[i];
  Vec2 value = Vec2::Zero();
  double power = 1.0;  // s^(k − order)
  for (int k = order; k < 6; ++k) {
    value += fallingFactorial(k, order) * power * c.row(k).transpose();
    power *= s;
  }
  return value / std::pow(h, order);
}

double MinimumJerkSpline::jerkCost() const noexcept {
  double cost = 0.0;
  for (std::size_t i = 0; i < coefficients_.size(); ++i) {
    const double h = times_[i + 1] - times_[i];
    const auto& c = coefficients_[i];
    for (int d = 0; d < 2; ++d) {
      // x''' (s) / h³ = (b3 + b4 s + b5 s²) / h³, squared and integrated over t = h·s.
      const double b3 = 6.0 * c(3, d);
      const double b4 = 24.0 * c(4, d);
      const double b5 = 60.0 * c(5, d);
      const double integral = b3 * b3 + b3 * b4 + (2.0 * b3 * b5 + b4 * b4) / 3.0 + b4 * b5 / 2.0 + b5 * b5 / 5.0;
      cost += integral / std::pow(h, 5);
    }
  }
  return cost;
}

namespace {

/// Quasi-Newton (BFGS) descent of `cost` from `theta`, with central-difference gradients and a
/// backtracking line search; at most 200 iterations.
template <class Cost>
Eigen::VectorXd minimizeBfgs(const Cost& cost, Eigen::VectorXd theta) {
  const auto gradient = [&](const Eigen::VectorXd& th) {
    constexpr double kStep = 1e-6;
    Eigen::VectorXd g(th.size());
    for (Eigen::Index i = 0; i < th.size(); ++i) {
      Eigen::VectorXd up = th, down = th;
      up(i) += kStep;
      down(i) -= kStep;
      g(i) = (cost(up) - cost(down)) / (2.0 * kStep);
    }
    return g;
  };
  double f = cost(theta);
  Eigen::VectorXd g = gradient(theta);
  Eigen::MatrixXd inverse_hessian = Eigen::MatrixXd::Identity(theta.size(), theta.size());
  for (int iteration = 0; iteration < 200; ++iteration) {
    Eigen::VectorXd direction = -inverse_hessian * g;
    if (direction.dot(g) >= 0.0) {  // not a descent direction: restart from steepest descent
      inverse_hessian.setIdentity();
      direction = -g;
    }
    double step = 1.0;
    double f_new = cost(theta + step * direction);
    while (!(f_new <= f + 1e-4 * step * direction.dot(g)) && step > 1e-12) {
      step *= 0.5;
      f_new = cost(theta + step * direction);
    }
    if (!(f_new < f)) break;
    const Eigen::VectorXd s = step * direction;
    theta += s;
    const Eigen::VectorXd g_new = gradient(theta);
    const Eigen::VectorXd y = g_new - g;
    const double sy = s.dot(y);
    if (sy > 1e-300) {
      const Eigen::VectorXd hy = inverse_hessian * y;
      inverse_hessian += ((sy + y.dot(hy)) / (sy * sy)) * (s * s.transpose()) - (hy * s.transpose() + s * hy.transpose()) / sy;
    }
    const bool converged = f - f_new <= 1e-10 * f;
    f = f_new;
    g = g_new;
    if (converged) break;
  }
  return theta;
}

}  // namespace

MinimumJerkSpline MinimumJerkSpline::withOptimalTimes(const std::vector<Vec2>& points, double duration) {
  HATTR_DEMAND(points.size() >= 2 && duration > 0.0, "{} points, duration {}", points.size(), duration);
  const auto segments = static_cast<Eigen::Index>(points.size() - 1);
  // The via times as a softmax of free parameters θ (θ_0 = 0): every gap stays positive and
  // the gaps always add up to the duration.
  const auto timesOf = [&](const Eigen::VectorXd& theta) {
    Eigen::VectorXd gaps(segments);
    gaps(0) = 0.0;
    gaps.tail(segments - 1) = theta;
    gaps = (gaps.array() - gaps.maxCoeff()).exp();
    gaps *= duration / gaps.sum();
    std::vector<double> times(points.size(), 0.0);
    for (Eigen::Index i = 0; i < segments; ++i) times[static_cast<std::size_t>(i + 1)] = times[static_cast<std::size_t>(i)] + gaps(i);
    times.back() = duration;
    return times;
  };
  // No gap below 2 % of the mean: beyond that the system grows ill-conditioned, and no writer
  // crosses a via segment that much faster than the others.
  const double min_gap = 0.02 * duration / static_cast<double>(segments);
  // Start from gaps proportional to the chord lengths, each at least 3 % of the mean (so the
  // start satisfies the 2 % bound).
  std::vector<double> chords;
  double total = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) total += chords.emplace_back((points[i] - points[i - 1]).norm());
  const double floor = 0.03 * total / static_cast<double>(segments);
  Eigen::VectorXd theta(segments - 1);
  for (Eigen::Index i = 1; i < segments; ++i) {
    theta(i - 1) = std::log(std::max(chords[static_cast<std::size_t>(i)], floor) / std::max(chords[0], floor));
  }
  if (segments == 1) return {points, timesOf(theta)};

  // The squared jerk over θ, descended by BFGS.
  const auto cost = [&](const Eigen::VectorXd& th) {
    const std::vector<double> times = timesOf(th);
    for (std::size_t i = 1; i < times.size(); ++i) {
      if (times[i] - times[i - 1] < min_gap) return std::numeric_limits<double>::infinity();
    }
    const auto spline = tryFit(points, times);
    return spline ? spline->jerkCost() : std::numeric_limits<double>::infinity();
  };
  theta = minimizeBfgs(cost, theta);
  return {points, timesOf(theta)};
}

double minimumJerkBlend(double s) noexcept {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
}

double minimumJerkBlendRate(double s) noexcept {
  if (s <= 0.0 || s >= 1.0) return 0.0;
  return 30.0 * s * s * (1.0 - s) * (1.0 - s);
}

}  // namespace hattr::sim::detail
