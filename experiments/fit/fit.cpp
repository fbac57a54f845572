#include "fit.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

namespace shimmer::experiments {

namespace {

// Ceres minimises 1/2 r^2; with r = sqrt(J) that is J / 2.
struct SqrtObjective {
  const std::function<double(double)>* objective;
  Fit1D* fit;
  bool operator()(const double* u, double* residual) const {
    const double p = std::exp(u[0]);
    const double j = (*objective)(p);
    fit->samples.push_back({p, j});
    ++fit->evaluations;
    residual[0] = std::sqrt(std::max(j, 0.0));
    return std::isfinite(j);
  }
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
  std::vector<double> points;
  for (int i = 0; i < sweep_points; ++i)
    points.push_back(sweep_points == 1 ? lo : lo * std::pow(hi / lo, double(i) / (sweep_points - 1)));
  for (double p : extra_points)
    if (p >= lo && p <= hi) points.push_back(p);
  for (double p : points) {
    fit.samples.push_back({p, objective(p)});
    ++fit.evaluations;
  }
  auto best = std::min_element(fit.samples.begin(), fit.samples.end(),
                               [](const auto& a, const auto& b) { return a.second < b.second; });
  fit.best = best->first;
  fit.objective = best->second;

  double u = std::log(fit.best);
  ceres::NumericDiffOptions diff;
  diff.relative_step_size = 0.1;
  ceres::Problem problem;
  auto* cost = new ceres::NumericDiffCostFunction<SqrtObjective, ceres::CENTRAL, 1, 1>(
      new SqrtObjective{&objective, &fit}, ceres::TAKE_OWNERSHIP, 1, diff);
  problem.AddResidualBlock(cost, nullptr, &u);
  problem.SetParameterLowerBound(&u, 0, std::log(lo));
  problem.SetParameterUpperBound(&u, 0, std::log(hi));
  ceres::Solver::Options options;
  options.max_num_iterations = 12;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  const double p = std::clamp(std::exp(u), lo, hi);
  const double j = objective(p);
  fit.samples.push_back({p, j});
  ++fit.evaluations;
  if (j < fit.objective) {
    fit.best = p;
    fit.objective = j;
    fit.ceres_improved = true;
  }
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
