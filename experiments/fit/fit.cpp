#include "shimmer/experiments/fit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace shimmer::experiments {

namespace {

// J on u = log p, each distinct u evaluated once (a rendered J costs seconds).
class MemoObjective {
 public:
  MemoObjective(const std::function<double(double)>& objective, Fit1D* fit) : objective_(objective), fit_(fit) {}
  double operator()(double u) {
    // Points that differ only by rounding (u + h - h) are the same render.
    const long long key = std::llround(u * 1e6);
    if (auto it = memo_.find(key); it != memo_.end()) return it->second;
    const double p = std::exp(u);
    const double j = objective_(p);
    fit_->samples.push_back({p, j});
    ++fit_->evaluations;
    return memo_[key] = j;
  }

 private:
  const std::function<double(double)>& objective_;
  Fit1D* fit_;
  std::map<long long, double> memo_;
};

// Newton on the smoothed gradient: the residual is the central difference
// g(u) = (J(u+h) - J(u-h)) / 2h, its derivative the second difference, and
// Ceres drives g to zero inside the sweep's bracket around the best point.
// h is a fixed step in log p (10 % in p), wide against the aliasing noise of
// a rendered J, which a small step would turn into meaningless slopes.
class SmoothedGradient : public ceres::SizedCostFunction<1, 1> {
 public:
  SmoothedGradient(MemoObjective* j, double h) : j_(j), h_(h) {}
  bool Evaluate(double const* const* u, double* residual, double** jacobian) const override {
    const double jm = (*j_)(u[0][0] - h_), j0 = (*j_)(u[0][0]), jp = (*j_)(u[0][0] + h_);
    residual[0] = (jp - jm) / (2 * h_);
    if (jacobian && jacobian[0]) jacobian[0][0] = (jp - 2 * j0 + jm) / (h_ * h_);
    return std::isfinite(residual[0]) && std::isfinite(j0);
  }

 private:
  MemoObjective* j_;
  double h_;
};

struct LogPowerResidual {
  double log_alpha, log_value;
  template <class T>
  bool operator()(const T* log_a, const T* b, T* residual) const {
    residual[0] = log_a[0] + b[0] * T(log_alpha) - T(log_value);
    return true;
  }
};

}  // namespace

Fit1D Minimize1D(const std::function<double(double)>& objective, double lo, double hi, int sweep_points,
                 const std::vector<double>& extra_points) {
  Fit1D fit;
  MemoObjective j(objective, &fit);
  const double ulo = std::log(lo), uhi = std::log(hi);
  std::vector<double> points;
  for (int i = 0; i < sweep_points; ++i)
    points.push_back(sweep_points == 1 ? ulo : ulo + (uhi - ulo) * double(i) / (sweep_points - 1));
  for (double p : extra_points)
    if (p >= lo && p <= hi) points.push_back(std::log(p));
  std::sort(points.begin(), points.end());
  int best = 0;
  for (int i = 0; i < int(points.size()); ++i)
    if (j(points[i]) < j(points[best])) best = i;
  fit.best = std::exp(points[best]);
  fit.objective = j(points[best]);

  // Refine inside the bracket of the best point's neighbours, which holds a
  // local minimum of the swept samples, with the difference steps kept
  // inside [lo, hi].
  const double h = 0.1;
  const double blo = std::max(best > 0 ? points[best - 1] : ulo, ulo + h);
  const double bhi = std::min(best + 1 < int(points.size()) ? points[best + 1] : uhi, uhi - h);
  if (blo < bhi) {
    double u = std::clamp(points[best], blo, bhi);
    ceres::Problem problem;
    problem.AddResidualBlock(new SmoothedGradient(&j, h), nullptr, &u);
    problem.SetParameterLowerBound(&u, 0, blo);
    problem.SetParameterUpperBound(&u, 0, bhi);
    ceres::Solver::Options options;
    // J is only known to about a percent, so stop at that level rather than
    // chase noise: each iteration costs up to three renders of every shot.
    options.max_num_iterations = 6;
    options.function_tolerance = 1e-4;
    options.parameter_tolerance = 1e-3;
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    j(u);  // Ceres' answer joins the samples
  }
  // Every sample is a candidate (Ceres' difference points may be the lowest);
  // any lower than the sweep's best came from the refinement.
  for (const auto& [p, v] : fit.samples)
    if (v < fit.objective) fit.best = p, fit.objective = v, fit.ceres_improved = true;
  return fit;
}

PowerLaw FitPowerLaw(const std::vector<double>& alpha, const std::vector<double>& value) {
  PowerLaw law;
  double log_a = 0, b = 0.5;
  ceres::Problem problem;
  for (std::size_t i = 0; i < alpha.size(); ++i)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LogPowerResidual, 1, 1, 1>(
                                 new LogPowerResidual{std::log(alpha[i]), std::log(value[i])}),
                             new ceres::CauchyLoss(0.2), &log_a, &b);
  ceres::Solver::Options options;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  law.a = std::exp(log_a);
  law.b = b;
  for (std::size_t i = 0; i < alpha.size(); ++i)
    law.residuals.push_back(log_a + b * std::log(alpha[i]) - std::log(value[i]));
  return law;
}

}  // namespace shimmer::experiments
