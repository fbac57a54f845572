// Adaptive Gauss-Kronrod (7/15) quadrature in double: the independent oracle
// the shading tests compare against. Bisects until the Gauss/Kronrod
// difference is below `rel_tol` of the interval's own estimate, so that
// positive integrands come out with that relative accuracy even where they
// are sharp (alpha = 1e-3) or tiny (far tails). `abs_tol` (per interval)
// stops refinement where an integrand is only rounding noise.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace shimmer::test {

inline double GaussKronrod15(const std::function<double(double)>& f, double a, double b, double* err) {
  static const double xk[8] = {0.991455371120812639, 0.949107912342758525, 0.864864423359769073, 0.741531185599394440,
                               0.586087235467691130, 0.405845151377397167, 0.207784955007898468, 0.000000000000000000};
  static const double wk[8] = {0.022935322010529225, 0.063092092629978553, 0.104790010322250184, 0.140653259715525919,
                               0.169004726639267903, 0.190350578064785410, 0.204432940075298892, 0.209482141084727828};
  static const double wg[4] = {0.129484966168869693, 0.279705391489276668, 0.381830050505118945, 0.417959183673469388};
  const double c = 0.5 * (a + b), h = 0.5 * (b - a);
  const double fc = f(c);
  double k = wk[7] * fc, g = wg[3] * fc;
  for (int i = 0; i < 7; ++i) {
    const double v = f(c - h * xk[i]) + f(c + h * xk[i]);
    k += wk[i] * v;
    if (i % 2 == 1) g += wg[i / 2] * v;
  }
  *err = std::abs((k - g) * h);
  return k * h;
}

inline double IntegrateInterval(const std::function<double(double)>& f, double a, double b, double rel_tol,
                                double abs_tol, int depth_left) {
  double err = 0;
  const double v = GaussKronrod15(f, a, b, &err);
  if (err <= std::max(rel_tol * std::abs(v), abs_tol) || depth_left <= 0) return v;
  const double m = 0.5 * (a + b);
  return IntegrateInterval(f, a, m, rel_tol, abs_tol, depth_left - 1) +
         IntegrateInterval(f, m, b, rel_tol, abs_tol, depth_left - 1);
}

// Integral of f over [a, b], split first at the given interior points (where
// f has a peak or kink) so that bisection finds them quickly. When f is itself
// an adaptive integral, its noise would make bisection run away: give the
// outer integral a looser tolerance and a small `max_depth`.
inline double Integrate(const std::function<double(double)>& f, double a, double b, std::vector<double> breaks = {},
                        double rel_tol = 1e-10, double abs_tol = 0, int max_depth = 50) {
  std::vector<double> pts{a};
  for (double x : breaks)
    if (x > a && x < b) pts.push_back(x);
  pts.push_back(b);
  std::sort(pts.begin() + 1, pts.end() - 1);
  double sum = 0;
  for (size_t i = 0; i + 1 < pts.size(); ++i)
    sum += IntegrateInterval(f, pts[i], pts[i + 1], rel_tol, abs_tol, max_depth);
  return sum;
}

}  // namespace shimmer::test
