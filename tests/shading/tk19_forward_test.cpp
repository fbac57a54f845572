// tk19-forward and tk19-forward-rect (variants.glsl): Tokuyoshi and
// Kaplanyan 2019's forward filter against its formulas written out here in
// double, the eigenvalue clamp, the bandwidth's dependence on the half
// vector's angle, and float against double on nearly rank-one kernels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "shimmer/shading/shading.h"

namespace shimmer::shading {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Sym2 {
  double xx, yy, xy;
};

// The NDF of slope s with roughness matrix R: GGX 1 / (pi sqrt(det R) (1 + s^T R^-1 s)^2),
// Beckmann exp(-s^T R^-1 s) / (pi sqrt(det R)).
double DensityWithMatrix(Ndf ndf, glm::dvec2 s, Sym2 r) {
  const double det = r.xx * r.yy - r.xy * r.xy;
  const double q = (r.yy * s.x * s.x + r.xx * s.y * s.y - 2 * r.xy * s.x * s.y) / det;
  if (ndf == Ndf::kBeckmann) return std::exp(-q) / (kPi * std::sqrt(det));
  return 1 / (kPi * std::sqrt(det) * (1 + q) * (1 + q));
}

// The kernel 2 sigma2 (dx dx^T + dy dy^T) with its eigenvalues clamped to kappa.
Sym2 ClampedKernel(glm::dvec2 dx, glm::dvec2 dy, double sigma2, double kappa) {
  const Sym2 k{2 * sigma2 * (dx.x * dx.x + dy.x * dy.x), 2 * sigma2 * (dx.y * dx.y + dy.y * dy.y),
               2 * sigma2 * (dx.x * dx.y + dy.x * dy.y)};
  const double mid = (k.xx + k.yy) / 2, rad = std::hypot((k.xx - k.yy) / 2, k.xy);
  const double l1 = mid + rad, l2 = mid - rad;
  if (l1 <= kappa) return k;
  // Eigenvectors of the larger and smaller eigenvalue.
  glm::dvec2 e1 = std::abs(k.xy) > 0 ? glm::normalize(glm::dvec2(k.xy, l1 - k.xx))
                                     : (k.xx >= k.yy ? glm::dvec2(1, 0) : glm::dvec2(0, 1));
  const glm::dvec2 e2{-e1.y, e1.x};
  const double c1 = std::min(l1, kappa), c2 = std::min(l2, kappa);
  return {c1 * e1.x * e1.x + c2 * e2.x * e2.x, c1 * e1.y * e1.y + c2 * e2.y * e2.y, c1 * e1.x * e1.y + c2 * e2.x * e2.y};
}

Footprint<double> WithProjected(glm::dvec2 hpp, glm::dvec2 dx, glm::dvec2 dy) {
  Footprint<double> f;
  f.hpp = hpp;
  f.dh_dx = dx;
  f.dh_dy = dy;
  return f;
}

const VariantInfo& Named(std::string_view name) { return *FindVariant(name); }

TEST(Tk19Forward, MatchesItsFormulaAtChosenFootprints) {
  const glm::dvec2 footprints[][2] = {
      {{0.02, 0.0}, {0.0, 0.01}},     // axis-aligned, small
      {{0.1, 0.05}, {-0.03, 0.08}},   // rotated
      {{0.3, 0.3}, {0.31, 0.29}},     // nearly rank one
      {{0.9, -0.2}, {0.4, 0.7}},      // large: both eigenvalues clamped at kappa = 0.18
      {{0.6, 0.0}, {0.0, 0.05}},      // one eigenvalue clamped
  };
  const glm::dvec2 slopes[] = {{0, 0}, {0.05, -0.02}, {0.4, 0.3}, {2, -1}};
  for (Ndf ndf : {Ndf::kGgx, Ndf::kBeckmann})
    for (glm::dvec2 alpha : {glm::dvec2(0.01), glm::dvec2(0.1, 0.03)})
      for (const auto& fp : footprints)
        for (glm::dvec2 s : slopes)
          for (double kappa : {0.18, 1e3}) {
            Params<double> p;
            p.sigma2 = 0.25;
            p.kappa = kappa;
            const Sym2 k = ClampedKernel(fp[0], fp[1], p.sigma2, kappa);
            const Sym2 r{alpha.x * alpha.x + k.xx, alpha.y * alpha.y + k.yy, k.xy};
            const auto got = EvaluateVariant<double>(Named("tk19-forward").id, ndf, alpha,
                                                     WithProjected(s, fp[0], fp[1]), p);
            const double want = DensityWithMatrix(ndf, s, r);
            const std::string where = std::string(NdfName(ndf)) + " alpha " + std::to_string(alpha.x) + " dx " +
                                      std::to_string(fp[0].x) + " s " + std::to_string(s.x) + " kappa " +
                                      std::to_string(kappa);
            EXPECT_NEAR(got.slope_density, want, 1e-10 * want + 1e-300) << where;
            EXPECT_NEAR(got.alpha_eff.x, std::sqrt(r.xx), 1e-12) << where;
            EXPECT_NEAR(got.alpha_eff.y, std::sqrt(r.yy), 1e-12) << where;
            const double q = 1 + glm::dot(s, s);
            EXPECT_NEAR(got.density, want * q * q, 1e-10 * want * q * q + 1e-300) << where;
          }
}

TEST(Tk19Forward, RectMatchesItsFormula) {
  const glm::dvec2 dx{0.3, -0.05}, dy{0.1, 0.02};
  const glm::dvec2 alpha{0.02, 0.2};
  for (double kappa : {0.01, 0.18, 10.0}) {
    Params<double> p;
    p.sigma2 = 0.25;
    p.kappa = kappa;
    const auto r = EvaluateVariant<double>(Named("tk19-forward-rect").id, Ndf::kGgx, alpha,
                                           WithProjected({0.1, 0.0}, dx, dy), p);
    const glm::dvec2 b = glm::abs(dx) + glm::abs(dy);  // (0.4, 0.07)
    for (int i = 0; i < 2; ++i) {
      const double a2 = std::min(1.0, alpha[i] * alpha[i] + std::min(2 * 0.25 * b[i] * b[i], kappa));
      EXPECT_NEAR(r.alpha_eff[i], std::sqrt(a2), 1e-12) << "axis " << i << " kappa " << kappa;
    }
    const double want = SlopeDensity<double>(Ndf::kGgx, {0.1, 0.0}, r.alpha_eff);
    EXPECT_NEAR(r.slope_density, want, 1e-12 * want);
  }
}

// At normal incidence h.xy and the slope agree to first order, so the
// paper's kernel is seed 000's parallelogram with its 0.5 px pixel filter;
// towards grazing the projected derivatives shrink by the chain rule, and
// so does the kernel (the paper's angle-aware bandwidth).
TEST(Tk19Forward, IsTheParallelogramAtNormalIncidenceAndNarrowsTowardsGrazing) {
  Footprint<double> f;
  f.dhpp_dx = {0.08, 0.02};
  f.dhpp_dy = {-0.01, 0.05};
  Params<double> p;
  p.kappa = 1e3;  // no clamp: the parallelogram has none
  for (Ndf ndf : {Ndf::kGgx, Ndf::kBeckmann}) {
    f.hpp = {0, 0};
    const auto forward = EvaluateVariant<double>(Named("tk19-forward").id, ndf, {0.03, 0.03}, WithChainedProjection(f), p);
    const auto par = EvaluateVariant<double>(Named("k16-beckmann-parallelogram").id, ndf, {0.03, 0.03}, f, p);
    EXPECT_NEAR(forward.slope_density, par.slope_density, 1e-12 * par.slope_density);
    EXPECT_NEAR(forward.alpha_eff.x, par.alpha_eff.x, 1e-12);
  }
  double previous = 1e30;
  for (double t : {0.0, 0.5, 1.0, 2.0, 5.0}) {
    f.hpp = {t, 0.3 * t};
    const auto r = EvaluateVariant<double>(Named("tk19-forward").id, Ndf::kGgx, {0.03, 0.03}, WithChainedProjection(f), p);
    const double widened = r.alpha_eff.x * r.alpha_eff.x - 0.03 * 0.03;
    EXPECT_LT(widened, previous) << "slope " << t;
    previous = widened;
  }
}

// The parallelogram's sigma2: 1 is the slide's bare U, which widens four
// times as much as the default 0.5 px filter.
TEST(Tk19Forward, ParallelogramSigma2ScalesItsKernel) {
  Footprint<double> f;
  f.dhpp_dx = {0.1, 0.0};
  f.dhpp_dy = {0.0, 0.04};
  const VariantInfo& v = Named("k16-beckmann-parallelogram");
  Params<double> p = ResolveParams(v, {}).value();
  EXPECT_EQ(p.sigma2, 0.25);
  const double a = 0.02;
  const double half = EvaluateVariant<double>(v.id, Ndf::kBeckmann, {a, a}, f, p).alpha_eff.x;
  p.sigma2 = 1;
  const double bare = EvaluateVariant<double>(v.id, Ndf::kBeckmann, {a, a}, f, p).alpha_eff.x;
  EXPECT_NEAR(half * half - a * a, 2 * 0.25 * 0.01, 1e-12);
  EXPECT_NEAR(bare * bare - a * a, 2 * 1.0 * 0.01, 1e-12);
}

// A nearly rank-one kernel, clamped and not: the sums-of-squares form keeps
// float within 1e-4 of double where the textbook determinant cancels.
TEST(Tk19Forward, FloatAgreesWithDoubleOnNearlyRankOneKernels) {
  for (Ndf ndf : {Ndf::kGgx, Ndf::kBeckmann})
    for (double a : {1e-3, 1e-2, 0.1})
      for (double scale : {1e-3, 0.1, 1.0, 1e3})
        for (double kappa : {0.18, 1e4})
          for (double along : {0.0, 1.0, 30.0}) {
            const glm::dvec2 dx = scale * glm::dvec2(1.0, 0.7), dy = scale * glm::dvec2(1.0 + 1e-5, 0.7);
            const glm::dvec2 across{-0.7, 1.0};
            const glm::dvec2 s = along * a * glm::normalize(dx) + 0.5 * a * glm::normalize(across);
            Params<double> pd;
            pd.kappa = kappa;
            Params<float> pf;
            pf.kappa = float(kappa);
            const auto d = EvaluateVariant<double>(Named("tk19-forward").id, ndf, {a, a}, WithProjected(s, dx, dy), pd);
            Footprint<float> ff;
            ff.hpp = glm::vec2(s);
            ff.dh_dx = glm::vec2(dx);
            ff.dh_dy = glm::vec2(dy);
            const auto f = EvaluateVariant<float>(Named("tk19-forward").id, ndf, {float(a), float(a)}, ff, pf);
            const std::string where = std::string(NdfName(ndf)) + " alpha " + std::to_string(a) + " scale " +
                                      std::to_string(scale) + " kappa " + std::to_string(kappa) + " along " +
                                      std::to_string(along);
            ASSERT_TRUE(std::isfinite(f.density)) << where;
            EXPECT_NEAR(f.slope_density, d.slope_density, 1e-4 * d.slope_density + 1e-30) << where;
          }
}

// The quad path differences h.xy, which stays in the unit disk: a neighbour
// at grazing (huge slope) moves it by at most 2, where the slope's own
// difference is unbounded.
TEST(Tk19Forward, ChainedProjectionIsTheDerivativeOfHxy) {
  const glm::dvec2 s{0.7, -0.4}, ds{1e-6, 3e-7};
  Footprint<double> f;
  f.hpp = s;
  f.dhpp_dx = ds;
  f = WithChainedProjection(f);
  auto hxy = [](glm::dvec2 t) { return t / std::sqrt(1 + glm::dot(t, t)); };
  const glm::dvec2 fd = hxy(s + ds) - hxy(s);
  EXPECT_NEAR(f.dh_dx.x, fd.x, 1e-12);
  EXPECT_NEAR(f.dh_dx.y, fd.y, 1e-12);
  EXPECT_LE(glm::length(hxy({1e8, 1e8}) - hxy({0, 0})), 1.0 + 1e-12);
}

}  // namespace
}  // namespace shimmer::shading
