// Fitting variant parameters (fp_max and friends) with Ceres Solver: a 1-D
// bounded minimisation of a rendered objective started from a coarse sweep,
// and a robust closed form fp_max(alpha) across materials.
#pragma once

#include <functional>
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

// Minimises J on [lo, hi] (lo > 0) on u = log p: a log-spaced sweep of
// `sweep_points` plus `extra_points`, then Ceres inside the bracket of the
// best swept point's neighbours, solving g(u) = 0 for the central-difference
// gradient g with a fixed step of 0.1 in u (10 % in p), large against the
// aliasing noise of a rendered J. The lowest J evaluated wins, so the result
// is never worse than any swept point. Each distinct p is evaluated once.
Fit1D Minimize1D(const std::function<double(double)>& objective, double lo, double hi, int sweep_points,
                 const std::vector<double>& extra_points = {});

// fp(alpha) = a * alpha^b by Ceres on log fp with a Cauchy loss (scale 0.2 in
// log units), so one odd material cannot drag the curve.
struct PowerLaw {
  double a = 0, b = 0;
  std::vector<double> residuals;  // log(fitted) - log(value), per point
};
PowerLaw FitPowerLaw(const std::vector<double>& alpha, const std::vector<double>& value);

}  // namespace shimmer::experiments
