// The GGX footprint-rectangle mean (seed 000) against an independent 2D
// adaptive quadrature: the seed's closed form, its failure in float32, and
// the stable evaluation's bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "quadrature.h"
#include "shimmer/renderer/shading.h"

namespace shimmer::shading {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Mean of the anisotropic GGX P22 over [cx +- fx] x [cy +- fy] by iterated
// adaptive quadrature of the density itself (nothing shared with the shading core).
double QuadratureRectMean(double cx, double cy, double fx, double fy, double ax, double ay) {
  auto p22 = [&](double x, double y) {
    const double u = x / ax, w = y / ay, t = 1 + u * u + w * w;
    return 1 / (kPi * ax * ay * t * t);
  };
  auto inner = [&](double x) {
    return test::Integrate([&](double y) { return p22(x, y); }, cy - fy, cy + fy, {0.0}, 1e-11);
  };
  const double integral = test::Integrate(inner, cx - fx, cx + fx, {0.0}, 1e-9, 0, 30);
  return integral / (4 * fx * fy);
}

struct RectCase {
  double alpha_x, alpha_y, fx, fy, cx, cy;
};

// alpha 1e-3..1, half-sides 1e-6..10 (also unequal), centres from the origin
// to 100 alpha and to slopes of several units (grazing).
std::vector<RectCase> HardGrid() {
  std::vector<RectCase> cases;
  const double alphas[] = {1e-3, 1e-2, 0.1, 0.5, 1.0};
  const double fps[] = {1e-6, 1e-4, 1e-2, 0.3, 10};
  for (double a : alphas)
    for (double fx : fps)
      for (double fy : fps) {
        const double centres[][2] = {{0, 0},     {a, 0},     {10 * a, 3 * a}, {100 * a, 0}, {100 * a, -100 * a},
                                     {3.0, 0.5}, {-5.0, 5.0}};
        for (const auto& c : centres) cases.push_back({a, a, fx, fy, c[0], c[1]});
      }
  // Anisotropic roughness too.
  for (double fx : fps) cases.push_back({1e-3, 0.3, fx, 0.01, 0.05, 0.2});
  return cases;
}

TEST(GgxRect, StableFloatWithinOneInAThousandOfQuadrature) {
  double worst = 0;
  RectCase worst_case{};
  for (const RectCase& c : HardGrid()) {
    const double oracle = QuadratureRectMean(c.cx, c.cy, c.fx, c.fy, c.alpha_x, c.alpha_y);
    const float v = GgxRectMeanStable<float>({float(c.cx), float(c.cy)}, {float(c.alpha_x), float(c.alpha_y)},
                                             {float(c.fx), float(c.fy)});
    ASSERT_GT(oracle, 0);
    const double rel = std::abs(double(v) / oracle - 1);
    if (rel > worst) worst = rel, worst_case = c;
  }
  EXPECT_LT(worst, 1e-3) << "alpha " << worst_case.alpha_x << " fp " << worst_case.fx << "," << worst_case.fy
                         << " centre " << worst_case.cx << "," << worst_case.cy;
  std::printf("k16-ggx-rect-stable float32: worst relative error %.3g over %zu cases\n", worst, HardGrid().size());
}

TEST(GgxRect, StableDoubleAgreesWithQuadratureTightly) {
  for (const RectCase& c : HardGrid()) {
    const double oracle = QuadratureRectMean(c.cx, c.cy, c.fx, c.fy, c.alpha_x, c.alpha_y);
    const double v = GgxRectMeanStable<double>({c.cx, c.cy}, {c.alpha_x, c.alpha_y}, {c.fx, c.fy});
    // The 8-point rule, not rounding, limits double: same 1e-4 bound.
    EXPECT_NEAR(v / oracle, 1.0, 1e-4) << c.alpha_x << " " << c.fx << " " << c.fy << " " << c.cx << " " << c.cy;
  }
}

TEST(GgxRect, SeedFormulaIsExactInDoubleWhereItDoesNotCancel) {
  // Footprints at least alpha (the seed's fp_min regime), centres near the lobe.
  for (double a : {1e-2, 0.1, 0.5}) {
    for (double f : {a, 3 * a}) {
      for (double cx : {0.0, a, 4 * a}) {
        const double oracle = QuadratureRectMean(cx, 0.5 * a, f, 0.7 * f, a, a);
        const double v = GgxRectMeanSeed<double>({cx, 0.5 * a}, {a, a}, {f, 0.7 * f});
        EXPECT_NEAR(v / oracle, 1.0, 1e-9) << "alpha " << a << " fp " << f << " cx " << cx;
      }
    }
  }
}

// On record: why k16-ggx-rect-stable exists. In float32 the seed's closed form
// loses everything for small or distant footprints (tens of percent, sign
// flips), which is why seed 000 clamps fp from below.
TEST(GgxRect, SeedFormulaCancelsCatastrophicallyInFloat) {
  double worst = 0;
  int wrong_sign_or_zero = 0;
  for (const RectCase& c : HardGrid()) {
    const double oracle = QuadratureRectMean(c.cx, c.cy, c.fx, c.fy, c.alpha_x, c.alpha_y);
    const float v = GgxRectMeanSeed<float>({float(c.cx), float(c.cy)}, {float(c.alpha_x), float(c.alpha_y)},
                                           {float(c.fx), float(c.fy)});
    if (!(v > 0)) ++wrong_sign_or_zero;
    if (std::isfinite(v)) worst = std::max(worst, std::abs(double(v) / oracle - 1));
  }
  EXPECT_GT(worst, 0.3);
  EXPECT_GT(wrong_sign_or_zero, 0);
  // A concrete case: alpha 0.01, a 1e-6 footprint five lobe widths off centre (14% off).
  const double oracle = QuadratureRectMean(0.05, 0.0, 1e-6, 1e-6, 0.01, 0.01);
  const float seed = GgxRectMeanSeed<float>({0.05f, 0.0f}, {0.01f, 0.01f}, {1e-6f, 1e-6f});
  const float stable = GgxRectMeanStable<float>({0.05f, 0.0f}, {0.01f, 0.01f}, {1e-6f, 1e-6f});
  EXPECT_GT(std::abs(seed / oracle - 1), 0.1);
  EXPECT_LT(std::abs(stable / oracle - 1), 1e-4);
  std::printf("seed float32: worst relative error %.3g, %d of %zu cases <= 0\n", worst, wrong_sign_or_zero,
              HardGrid().size());
}

TEST(GgxRect, TinyFootprintIsThePointDensity) {
  for (double a : {1e-3, 0.05, 1.0})
    for (double cx : {0.0, 2 * a, 7.0}) {
      const glm::dvec2 c{cx, -0.3 * a}, al{a, 1.5 * a};
      const double point = SlopeDensity<double>(Ndf::kGgx, c, al);
      EXPECT_NEAR(GgxRectMeanStable<double>(c, al, {0, 0}) / point, 1.0, 1e-12);
      EXPECT_NEAR(GgxRectMeanStable<float>(glm::vec2(c), glm::vec2(al), {0, 0}) / point, 1.0, 1e-5);
    }
}

}  // namespace
}  // namespace shimmer::shading
