// The searches fits run, with Ceres Solver, on any objective (no spec, job
// or render here): bounded minimisation of a noisy objective from a coarse
// sweep or grid, and a robust closed form fp_max(alpha) across materials.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace shimmer::experiments {

struct Fit1D {
  double best = 0;              // the parameter value
  double objective = 0;         // J(best)
  int evaluations = 0;          // calls of J, sweep included
  bool ceres_improved = false;  // false when the sweep's best point stood
  // evaluations == samples.size(): distinct values of p
  std::vector<std::pair<double, double>> samples;  // (p, J(p)) of every evaluation
};

// Minimises J on [lo, hi] (lo > 0) on u = log p: MinimizeND on one
// logarithmic axis. A log-spaced sweep of `sweep_points` plus `extra_points`,
// then Ceres within one sweep step either side of the best point, solving
// g(u) = 0 for the central-difference
// gradient g with a fixed step of 0.1 in u (10 % in p), large against the
// aliasing noise of a rendered J. The lowest J evaluated wins, so the result
// is never worse than any swept point. Each distinct p is evaluated once.
Fit1D Minimize1D(const std::function<double(double)>& objective, double lo, double hi, int sweep_points,
                 const std::vector<double>& extra_points = {});

// One parameter of a joint fit: its bounds, searched on log p when lo > 0
// (scales: fp_max, sigma2) and on p itself otherwise (biases).
struct FitAxis {
  double lo = 0, hi = 1;
  bool Logarithmic() const { return lo > 0; }
};

// Where a fitted value sits on its axis: a value within 0.1 % of the axis'
// span (in log p on logarithmic axes) of an end is on that bound, and the
// search stopped there rather than at a minimum of J.
enum class Bound { kInside, kLower, kUpper };
Bound OnBound(double value, const FitAxis& axis);

struct FitND {
  std::vector<double> best;     // a value per axis
  double objective = 0;         // J(best)
  int evaluations = 0;          // calls of J, grid included
  bool ceres_improved = false;  // false when the grid's best point stood
  std::vector<std::pair<std::vector<double>, double>> samples;  // (p, J(p)) of every evaluation
};

// Minimises J over the box of `axes` jointly: a grid of `grid_points` per
// axis (log-spaced on logarithmic axes) plus `extra_points` inside the box,
// then Ceres inside the grid cell around the best point (one tick either way
// per axis), solving g(u) = 0 for the central-difference gradient g with the
// difference Hessian as its Jacobian, at a fixed step (0.1 in log p, 5 % of
// the range on linear axes) wide against a rendered J's aliasing noise. The
// lowest J evaluated wins, so the result is never worse than any grid point;
// each distinct point is evaluated once.
FitND MinimizeND(const std::function<double(const std::vector<double>&)>& objective, const std::vector<FitAxis>& axes,
                 int grid_points, const std::vector<std::vector<double>>& extra_points = {});

// fp(alpha) = a * alpha^b by Ceres on log fp with a Cauchy loss (scale 0.2 in
// log units), so one odd material cannot drag the curve.
struct PowerLaw {
  double a = 0, b = 0;
  std::vector<double> residuals;  // log(fitted) - log(value), per point
  // 95 % intervals of a and b: Student's t on n - 2 degrees of freedom
  // about Ceres' covariance of (log a, b), scaled by the residuals' variance
  // sum r^2 / (n - 2). NaN with fewer than three points (two points fit any
  // law exactly: no residual, no interval).
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  double a_lo = kNaN, a_hi = kNaN, b_lo = kNaN, b_hi = kNaN;
  bool HasInterval() const { return a_lo == a_lo && b_lo == b_lo; }
};
PowerLaw FitPowerLaw(const std::vector<double>& alpha, const std::vector<double>& value);

// Student's t, the two-sided 95 % quantile for `df` degrees of freedom.
double StudentT975(int df);

}  // namespace shimmer::experiments
