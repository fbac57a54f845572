#include "shimmer/experiments/minimize.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace shimmer::experiments {

namespace {

struct LogPowerResidual {
  double log_alpha, log_value;
  template <class T>
  bool operator()(const T* log_a, const T* b, T* residual) const {
    residual[0] = log_a[0] + b[0] * T(log_alpha) - T(log_value);
    return true;
  }
};

// J is only known to about a percent, so the refinement stops at that level
// rather than chase noise, and after a few iterations (each renders again).
ceres::Solver::Options RefinementOptions() {
  ceres::Solver::Options options;
  options.max_num_iterations = 6;
  options.function_tolerance = 1e-4;
  options.parameter_tolerance = 1e-3;
  options.logging_type = ceres::SILENT;
  return options;
}

// The ND search's coordinates: u = log p on logarithmic axes, p otherwise.
double ToU(const FitAxis& a, double p) { return a.Logarithmic() ? std::log(p) : p; }
double FromU(const FitAxis& a, double u) { return a.Logarithmic() ? std::exp(u) : u; }
double StepU(const FitAxis& a) { return a.Logarithmic() ? 0.1 : 0.05 * (a.hi - a.lo); }

class MemoObjectiveND {
 public:
  MemoObjectiveND(const std::function<double(const std::vector<double>&)>& objective, const std::vector<FitAxis>& axes,
                  FitND* fit)
      : objective_(objective), axes_(axes), fit_(fit) {}
  double operator()(const std::vector<double>& u) {
    std::vector<long long> key;
    for (std::size_t i = 0; i < u.size(); ++i) key.push_back(std::llround(u[i] / StepU(axes_[i]) * 1e5));
    if (auto it = memo_.find(key); it != memo_.end()) return it->second;
    std::vector<double> p;
    for (std::size_t i = 0; i < u.size(); ++i) p.push_back(FromU(axes_[i], u[i]));
    const double j = objective_(p);
    fit_->samples.push_back({p, j});
    ++fit_->evaluations;
    return memo_[key] = j;
  }

 private:
  const std::function<double(const std::vector<double>&)>& objective_;
  const std::vector<FitAxis>& axes_;
  FitND* fit_;
  std::map<std::vector<long long>, double> memo_;
};

// Newton on the smoothed gradient: the residual is the central
// difference gradient g_i(u) = (J(u + h_i e_i) - J(u - h_i e_i)) / 2 h_i, its
// Jacobian the difference Hessian (the mixed terms from the four corners
// u +- h_i e_i +- h_j e_j), and Ceres drives g to zero inside the grid cell.
// h is a fixed step (10 % in p on logarithmic axes), wide against the
// aliasing noise of a rendered J, which a small step would turn into
// meaningless slopes.
class SmoothedGradientND : public ceres::CostFunction {
 public:
  SmoothedGradientND(MemoObjectiveND* j, std::vector<double> h) : j_(j), h_(std::move(h)) {
    set_num_residuals(int(h_.size()));
    mutable_parameter_block_sizes()->push_back(int(h_.size()));
  }
  bool Evaluate(double const* const* params, double* residual, double** jacobian) const override {
    const std::size_t n = h_.size();
    const std::vector<double> u(params[0], params[0] + n);
    auto at = [&](std::size_t i, double si, std::size_t k, double sk) {
      std::vector<double> v = u;
      v[i] += si * h_[i];
      v[k] += sk * h_[k];
      return (*j_)(v);
    };
    const double j0 = (*j_)(u);
    if (!std::isfinite(j0)) return false;
    std::vector<double> jp(n), jm(n);
    for (std::size_t i = 0; i < n; ++i) {
      jp[i] = at(i, 1, i, 0);
      jm[i] = at(i, -1, i, 0);
      residual[i] = (jp[i] - jm[i]) / (2 * h_[i]);
      if (!std::isfinite(residual[i])) return false;
    }
    if (jacobian && jacobian[0])
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < n; ++k) {
          double d;
          if (i == k) {
            d = (jp[i] - 2 * j0 + jm[i]) / (h_[i] * h_[i]);
          } else if (k < i) {
            d = jacobian[0][k * n + i];  // symmetric: computed on row k
          } else {
            d = (at(i, 1, k, 1) - at(i, 1, k, -1) - at(i, -1, k, 1) + at(i, -1, k, -1)) / (4 * h_[i] * h_[k]);
          }
          if (!std::isfinite(d)) return false;
          jacobian[0][i * n + k] = d;
        }
    return true;
  }

 private:
  MemoObjectiveND* j_;
  std::vector<double> h_;
};

}  // namespace

FitND MinimizeND(const std::function<double(const std::vector<double>&)>& objective, const std::vector<FitAxis>& axes,
                 int grid_points, const std::vector<std::vector<double>>& extra_points) {
  FitND fit;
  MemoObjectiveND j(objective, axes, &fit);
  const std::size_t n = axes.size();
  // Grid coordinates per axis, then every combination (the last axis fastest).
  std::vector<std::vector<double>> ticks(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double ulo = ToU(axes[i], axes[i].lo), uhi = ToU(axes[i], axes[i].hi);
    for (int k = 0; k < grid_points; ++k)
      ticks[i].push_back(grid_points == 1 ? ulo : ulo + (uhi - ulo) * double(k) / (grid_points - 1));
  }
  std::vector<std::vector<double>> points;
  std::vector<int> index(n, 0);
  for (bool more = n > 0; more;) {
    std::vector<double> u(n);
    for (std::size_t i = 0; i < n; ++i) u[i] = ticks[i][index[i]];
    points.push_back(u);
    more = false;
    for (std::size_t i = n; i-- > 0;) {
      if (++index[i] < grid_points) {
        more = true;
        break;
      }
      index[i] = 0;
    }
  }
  for (const std::vector<double>& p : extra_points) {
    bool inside = p.size() == n;
    for (std::size_t i = 0; inside && i < n; ++i) inside = p[i] >= axes[i].lo && p[i] <= axes[i].hi;
    if (!inside) continue;
    std::vector<double> u(n);
    for (std::size_t i = 0; i < n; ++i) u[i] = ToU(axes[i], p[i]);
    points.push_back(u);
  }
  std::size_t best = 0;
  for (std::size_t k = 0; k < points.size(); ++k)
    if (j(points[k]) < j(points[best])) best = k;
  fit.objective = j(points[best]);
  for (std::size_t i = 0; i < n; ++i) fit.best.push_back(FromU(axes[i], points[best][i]));

  // Refine inside the grid cell around the best point (one tick either way
  // on every axis), the difference steps kept inside the bounds.
  std::vector<double> u = points[best], h(n);
  std::vector<double> blo(n), bhi(n);
  bool room = n > 0;
  for (std::size_t i = 0; i < n; ++i) {
    h[i] = StepU(axes[i]);
    const double ulo = ToU(axes[i], axes[i].lo), uhi = ToU(axes[i], axes[i].hi);
    const double tick = grid_points > 1 ? (uhi - ulo) / (grid_points - 1) : uhi - ulo;
    blo[i] = std::max(u[i] - tick, ulo + h[i]);
    bhi[i] = std::min(u[i] + tick, uhi - h[i]);
    room = room && blo[i] < bhi[i];
    u[i] = std::clamp(u[i], blo[i], bhi[i]);
  }
  if (room) {
    ceres::Problem problem;
    problem.AddResidualBlock(new SmoothedGradientND(&j, h), nullptr, u.data());
    for (std::size_t i = 0; i < n; ++i) {
      problem.SetParameterLowerBound(u.data(), int(i), blo[i]);
      problem.SetParameterUpperBound(u.data(), int(i), bhi[i]);
    }
    ceres::Solver::Summary summary;
    ceres::Solve(RefinementOptions(), &problem, &summary);  // an iteration: up to 2N^2 + 1 renders a shot
    j(u);
  }
  for (const auto& [p, v] : fit.samples)
    if (v < fit.objective) fit.best = p, fit.objective = v, fit.ceres_improved = true;
  return fit;
}

// The one-parameter search is the joint one on a single logarithmic axis
// (same sweep, same bracket, same Ceres refinement, same memo).
Fit1D Minimize1D(const std::function<double(double)>& objective, double lo, double hi, int sweep_points,
                 const std::vector<double>& extra_points) {
  std::vector<std::vector<double>> extra;
  for (double p : extra_points) extra.push_back({p});
  const FitND nd = MinimizeND([&](const std::vector<double>& p) { return objective(p[0]); }, {FitAxis{lo, hi}},
                              sweep_points, extra);
  Fit1D fit;
  fit.best = nd.best.at(0);
  fit.objective = nd.objective;
  fit.evaluations = nd.evaluations;
  fit.ceres_improved = nd.ceres_improved;
  for (const auto& [p, j] : nd.samples) fit.samples.push_back({p.at(0), j});
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
  double squares = 0;
  for (std::size_t i = 0; i < alpha.size(); ++i) {
    law.residuals.push_back(log_a + b * std::log(alpha[i]) - std::log(value[i]));
    squares += law.residuals.back() * law.residuals.back();
  }
  const int df = int(alpha.size()) - 2;
  if (df < 1) return law;
  ceres::Covariance covariance({});
  const std::vector<std::pair<const double*, const double*>> blocks = {{&log_a, &log_a}, {&b, &b}};
  if (!covariance.Compute(blocks, &problem)) return law;  // rank-deficient: one alpha only
  double var_log_a = 0, var_b = 0;
  covariance.GetCovarianceBlock(&log_a, &log_a, &var_log_a);
  covariance.GetCovarianceBlock(&b, &b, &var_b);
  const double scale = squares / df, t = StudentT975(df);
  const double half_log_a = t * std::sqrt(var_log_a * scale), half_b = t * std::sqrt(var_b * scale);
  law.a_lo = std::exp(log_a - half_log_a), law.a_hi = std::exp(log_a + half_log_a);
  law.b_lo = b - half_b, law.b_hi = b + half_b;
  return law;
}

Bound OnBound(double value, const FitAxis& axis) {
  const bool log = axis.Logarithmic() && value > 0;
  auto at = [&](double x) { return log ? std::log(x) : x; };
  const double span = at(axis.hi) - at(axis.lo), tolerance = 1e-3 * std::abs(span);
  if (std::abs(at(value) - at(axis.lo)) <= tolerance) return Bound::kLower;
  if (std::abs(at(value) - at(axis.hi)) <= tolerance) return Bound::kUpper;
  return Bound::kInside;
}

// By degrees of freedom (1..30), then the Cornish-Fisher expansion about the
// normal quantile, within 1e-3 beyond.
double StudentT975(int df) {
  static const double table[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                                 2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
                                 2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  if (df >= 1 && df <= 30) return table[df - 1];
  const double z = 1.959964;
  return z + (z * z * z + z) / (4.0 * df) + (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96.0 * df * df);
}

}  // namespace shimmer::experiments
