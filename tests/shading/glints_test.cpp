// Glints (glints.glsl, seed 001): the biscale NDF's normalisation, the
// stochastic process's convergence to it at large footprints, its binomial
// draws, determinism and continuity under sub-pixel motion, and degenerate
// inputs in float and double.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "quadrature.h"
#include "shimmer/shading/shading.h"

namespace shimmer::shading {
namespace {

constexpr double kPi = 3.14159265358979323846;

MaterialDesc Glints(double alpha, double alpha_l, double density) {
  MaterialDesc m;
  m.ndf = Ndf::kGlints;
  m.alpha = {alpha, alpha};
  m.glint_alpha_l = alpha_l;
  m.glint_density = density;
  return m;
}

GlintFootprint<double> Footprint(glm::dvec2 uv, double width) {
  GlintFootprint<double> f;
  f.uv = uv;
  f.duvdx = {width, 0};
  f.duvdy = {0, width};
  return f;
}

double BeckmannSlopeDensity(glm::dvec2 s, double alpha) {
  return std::exp(-glm::dot(s, s) / (alpha * alpha)) / (kPi * alpha * alpha);
}

// D_g is Beckmann with alpha_g^2 = alpha^2 + alpha_l^2, and normalised:
// the integral of D(h) (n.h) over the hemisphere is 1.
TEST(Glints, SmoothGlobalNdfIsNormalisedBeckmann) {
  for (double alpha : {0.05, 0.3, 0.8}) {
    const MaterialDesc m = Glints(alpha, 0.2 * alpha, 1e4);
    const double ag = std::sqrt(alpha * alpha + 0.04 * alpha * alpha);
    auto d = [&](double theta, double phi) {
      const double r = std::tan(theta);
      const glm::dvec2 s{r * std::cos(phi), r * std::sin(phi)};
      return EvaluateGlints<double>(GlintMode::kSmooth, m, s, {}).density;
    };
    auto over_phi = [&](double theta) {
      return test::Integrate([&](double phi) { return d(theta, phi); }, 0, 2 * kPi, {}, 1e-10) * std::cos(theta) *
             std::sin(theta);
    };
    const double total = test::Integrate(over_phi, 0, kPi / 2, {std::atan(ag), std::atan(3 * ag)}, 1e-9);
    EXPECT_NEAR(total, 1.0, 1e-3) << "alpha " << alpha;
    const glm::dvec2 s{0.3 * ag, -0.2 * ag};
    EXPECT_NEAR(EvaluateGlints<double>(GlintMode::kSmooth, m, s, {}).slope_density, BeckmannSlopeDensity(s, ag),
                1e-9 * BeckmannSlopeDensity(s, ag));
  }
}

// At a footprint of thousands of cells every cell holds millions of
// microdetails, k / n is the bin's probability, and the process is the
// smooth D_m * (box * tent) of the perturbed bins: its mean over positions
// is within 3 % of D_g's peak of D_g everywhere, and one pixel alone within
// 6 % (the few cells' own bin offsets). The box * tent lobe has the
// variance of D_l but not its Gaussian shape; at alpha_l / alpha = 0.1 that
// difference is far below these bounds.
TEST(Glints, LargeFootprintsConvergeToTheGlobalNdf) {
  const double alpha = 0.3, alpha_l = 0.03;
  const MaterialDesc m = Glints(alpha, alpha_l, 1e4);
  const double ag = std::sqrt(alpha * alpha + alpha_l * alpha_l);
  const double peak = BeckmannSlopeDensity({0, 0}, ag);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-100, 100);
  for (glm::dvec2 s : {glm::dvec2{0, 0}, glm::dvec2{0.1, 0}, glm::dvec2{0.2, 0.15}, glm::dvec2{-0.35, 0.1},
                       glm::dvec2{0.5, -0.4}, glm::dvec2{0.9, 0.0}}) {
    double sum = 0;
    const int n = 48;
    for (int i = 0; i < n; ++i) {
      const double v =
          EvaluateGlints<double>(GlintMode::kFiltered, m, s, Footprint({pos(rng), pos(rng)}, 40.0)).slope_density;
      EXPECT_NEAR(v, BeckmannSlopeDensity(s, ag), 0.06 * peak) << "slope " << s.x << "," << s.y;
      sum += v;
    }
    EXPECT_NEAR(sum / n, BeckmannSlopeDensity(s, ag), 0.03 * peak) << "slope " << s.x << "," << s.y;
  }
}

// The process integrates to 1 over the slope plane in expectation: each
// cell's draws sum to the microdetails it holds. Checked for sparse cells
// (the finest level: one microdetail per cell) and a filtered footprint of a
// few cells, averaged over positions.
TEST(Glints, ProcessIntegratesToOneInExpectation) {
  const MaterialDesc m = Glints(0.2, 0.04, 1e4);
  const double ag = std::sqrt(0.04 + 0.0016);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(-50, 50);
  for (GlintMode mode : {GlintMode::kPoint, GlintMode::kFiltered}) {
    double mean = 0;
    const int positions = 100;
    for (int i = 0; i < positions; ++i) {
      const GlintFootprint<double> f = Footprint({pos(rng), pos(rng)}, 0.03);
      // Midpoint rule on a grid finer than the bins (side sqrt(2) 0.04):
      // exact for the piecewise-bilinear density up to its kinks.
      const double h = 0.014, r = 4 * ag;
      double integral = 0;
      for (double x = -r + h / 2; x < r; x += h)
        for (double y = -r + h / 2; y < r; y += h)
          integral += EvaluateGlints<double>(mode, m, {x, y}, f).slope_density * h * h;
      mean += integral / positions;
    }
    // Standard error of the mean: a cell's total is a sum of Bernoulli draws
    // of about one microdetail, so the 100 positions give ~0.07 at most.
    EXPECT_NEAR(mean, 1.0, 0.2) << "mode " << int(mode);
  }
}

// The expected number of reflecting microdetails is the binomial mean n p,
// its variance that of N ~ floor(n) + Bernoulli(frac n) microdetails each
// reflecting with probability p: n p (1 - p) + f (1 - f) p^2. Over
// stratified uniforms (the quantile function integrated exactly, no
// sampling noise) for sparse cells (inversion), dense ones (normal
// approximation) and nearly full bins (inversion of the failures).
TEST(Glints, BinomialDrawHasTheBinomialMeanAndVariance) {
  const int strata = 100000;
  for (double n : {0.5, 1.0, 3.7, 20.0, 1000.0, 1e7})
    for (double p : {1e-6, 1e-3, 0.05, 0.3, 0.9, 0.999}) {
      double sum = 0, sum2 = 0;
      const double f = n - std::floor(n);
      // u2 decides N: below f it adds one microdetail.
      for (auto [u2, weight] : {std::pair{0.5 * f, f}, std::pair{0.5 * (1 + f), 1 - f}}) {
        for (int i = 0; i < strata; ++i) {
          const double k = GlintBinomial<double>(n, p, (i + 0.5) / strata, u2);
          ASSERT_GE(k, 0.0);
          ASSERT_LE(k, std::ceil(n) + 1e-9);
          sum += weight * k / strata;
          sum2 += weight * k * k / strata;
        }
      }
      const double var = sum2 - sum * sum;
      const double expect_mean = n * p, expect_var = n * p * (1 - p) + f * (1 - f) * p * p;
      EXPECT_NEAR(sum, expect_mean, 2e-3 * expect_mean + 1e-4) << "n " << n << " p " << p;
      EXPECT_NEAR(var, expect_var, 2e-2 * expect_var + 1e-3) << "n " << n << " p " << p;
    }
}

TEST(Glints, BinomialDrawIsMonotoneInTheUniform) {
  for (double n : {1.0, 12.0, 500.0})
    for (double p : {0.01, 0.5, 0.97}) {
      double last = -1;
      for (int i = 0; i < 5000; ++i) {
        const double k = GlintBinomial<double>(n, p, (i + 0.5) / 5000, 0.5);
        EXPECT_GE(k, last) << "n " << n << " p " << p << " u " << (i + 0.5) / 5000;
        last = k;
      }
    }
}

// The bin probability is the Beckmann marginal's integral: against
// quadrature of the density, far tails included (relative accuracy there is
// what keeps n p from inventing sparkles).
TEST(Glints, BinProbabilityMatchesQuadratureIntoTheTails) {
  const double alpha = 0.25;
  auto density = [alpha](double x) { return std::exp(-x * x / (alpha * alpha)) / (std::sqrt(kPi) * alpha); };
  for (double lo : {-1.0, -0.3, -0.02, 0.0, 0.1, 0.5, 0.9})
    for (double width : {0.01, 0.04, 0.3}) {
      const double expect = test::Integrate(density, lo, lo + width, {}, 1e-12);
      // erfc's relative error 1.2e-7 is absolute near the lobe, where a bin
      // is a difference of two erfc near 1: hence the absolute 2e-7.
      EXPECT_NEAR(GlintInterval<double>(lo, lo + width, alpha), expect, 1e-6 * expect + 2e-7 * (lo < 0.3))
          << "[" << lo << ", " << lo + width << "]";
    }
}

// Deterministic in its seed (the 4D index): the same point, footprint and
// half vector give the same value, every time and in a fresh evaluation.
// Under sub-pixel motion (a thousandth of a cell) the filtered and point
// values move continuously, while the naive baseline jumps where the point
// crosses a cell.
TEST(Glints, DeterministicAndContinuousUnderSubPixelMotion) {
  const MaterialDesc m = Glints(0.3, 0.03, 1e4);
  const double cell = 0.01, peak = BeckmannSlopeDensity({0, 0}, 0.3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-20, 20), slope(-0.3, 0.3), width(0.0, 0.2);
  int jumps_filtered = 0, jumps_point = 0, naive_changed = 0;
  const int trials = 2000;
  for (int i = 0; i < trials; ++i) {
    const glm::dvec2 uv{pos(rng), pos(rng)}, s{slope(rng), slope(rng)};
    const double w = width(rng);
    const GlintFootprint<double> f = Footprint(uv, w);
    const double a = EvaluateGlints<double>(GlintMode::kFiltered, m, s, f).slope_density;
    EXPECT_EQ(a, EvaluateGlints<double>(GlintMode::kFiltered, m, s, f).slope_density);
    GlintFootprint<double> moved = Footprint(uv + glm::dvec2(1e-3 * cell, 0.7e-3 * cell), w * (1 + 1e-3));
    const double b = EvaluateGlints<double>(GlintMode::kFiltered, m, s + glm::dvec2(1e-6), moved).slope_density;
    // A level-0 cell with one microdetail reflecting gives 1 / w^2 = 560;
    // continuity bounds the change by ~1e-2 of that for this motion.
    jumps_filtered += std::abs(a - b) > 0.05 * peak + 1e-2 * std::max(a, b);
    const double pa = EvaluateGlints<double>(GlintMode::kPoint, m, s, f).slope_density;
    const double pb = EvaluateGlints<double>(GlintMode::kPoint, m, s + glm::dvec2(1e-6), moved).slope_density;
    jumps_point += std::abs(pa - pb) > 0.05 * peak + 1e-2 * std::max(pa, pb);
    // The naive baseline over a half-cell move: a new cell, a new draw.
    GlintFootprint<double> half = Footprint(uv + glm::dvec2(0.5 * cell, 0), w);
    naive_changed += EvaluateGlints<double>(GlintMode::kNaive, m, s, f).slope_density !=
                     EvaluateGlints<double>(GlintMode::kNaive, m, s, half).slope_density;
  }
  // The filtered footprint's probe count is an integer; where it steps the
  // value may jump: allowed in 1 % of the trials.
  EXPECT_LE(jumps_filtered, trials / 100);
  EXPECT_EQ(jumps_point, 0);
  EXPECT_GT(naive_changed, 0);
}

// No NaN, Inf or negative value for degenerate footprints (zero, huge,
// infinite, NaN, extremely anisotropic, grazing half vectors, extreme
// materials), float and double, every mode.
TEST(Glints, DegenerateInputsGiveFiniteNonNegativeValues) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<MaterialDesc> materials = {Glints(0.3, 0.03, 1e4), Glints(1e-4, 1e-4, 1e12), Glints(1, 1, 1e-6),
                                         Glints(0.05, 1, 1)};
  std::vector<glm::dvec2> slopes = {{0, 0}, {1e8, 0}, {-3e7, 9e7}, {1e-30, -1e-30}, {50, 50}};
  std::vector<std::pair<glm::dvec2, glm::dvec2>> derivs = {
      {{0, 0}, {0, 0}},     {{1e30, 0}, {0, 1e30}}, {{inf, 0}, {0, inf}}, {{nan, 0}, {0, 1}},
      {{1, 0}, {1, 1e-9}},  {{1e-6, 0}, {0, 50}},   {{-3, 4}, {4, 3}},       {{1e9, 3e8}, {-1e-9, 1e-8}}};
  std::vector<glm::dvec2> points = {{0, 0}, {-1e12, 1e12}, {inf, 0}, {nan, nan}, {1.5, -2.25}};
  for (const MaterialDesc& m : materials)
    for (glm::dvec2 s : slopes)
      for (auto [dx, dy] : derivs)
        for (glm::dvec2 uv : points)
          for (GlintMode mode : {GlintMode::kFiltered, GlintMode::kPoint, GlintMode::kNaive, GlintMode::kSmooth,
                                 GlintMode::kCounting, GlintMode::kDb23}) {
            GlintFootprint<double> fd{uv, dx, dy, 1.0};
            GlintFootprint<float> ff{glm::vec2(uv), glm::vec2(dx), glm::vec2(dy), 1.0f};
            const auto d = EvaluateGlints<double>(mode, m, s, fd);
            const auto f = EvaluateGlints<float>(mode, m, glm::vec2(s), ff);
            for (double v : {d.density, d.slope_density, double(f.density), double(f.slope_density)}) {
              ASSERT_TRUE(std::isfinite(v)) << "mode " << int(mode) << " slope " << s.x << " dx " << dx.x;
              ASSERT_GE(v, 0.0);
            }
            const auto cd = CountGlints<double>(mode, m, s, fd);
            const auto cf = CountGlints<float>(mode, m, glm::vec2(s), ff);
            for (double v : {cd.count, cd.total, double(cf.count), double(cf.total)}) {
              ASSERT_TRUE(std::isfinite(v)) << "count, mode " << int(mode) << " slope " << s.x << " dx " << dx.x;
              ASSERT_GE(v, 0.0);
            }
          }
}

// Float against double on ordinary inputs: the same draws (the hashes are
// integer), the same value to float rounding, except where float moves a
// point across a cell or bin edge or a draw's uniform across a step of the
// binomial's CDF: at most 2 % of the inputs.
TEST(Glints, FloatAgreesWithDouble) {
  const MaterialDesc m = Glints(0.3, 0.03, 1e4);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> pos(-10, 10), slope(-0.6, 0.6), width(0.0, 0.3);
  for (GlintMode mode : {GlintMode::kFiltered, GlintMode::kPoint, GlintMode::kNaive, GlintMode::kSmooth,
                         GlintMode::kCounting, GlintMode::kDb23}) {
    int differ = 0;
    const int trials = 3000;
    for (int i = 0; i < trials; ++i) {
      const glm::dvec2 uv{pos(rng), pos(rng)}, s{slope(rng), slope(rng)};
      const glm::dvec2 dx{width(rng), 0.3 * width(rng)}, dy{0.2 * width(rng), width(rng)};
      const double d = EvaluateGlints<double>(mode, m, s, {uv, dx, dy, 1.0}).density;
      const float f =
          EvaluateGlints<float>(mode, m, glm::vec2(s), {glm::vec2(uv), glm::vec2(dx), glm::vec2(dy), 1.0f}).density;
      differ += std::abs(f - d) > 1e-3 * d + 1e-4;
    }
    EXPECT_LE(differ, trials / 50) << "mode " << int(mode);
  }
}

}  // namespace
}  // namespace shimmer::shading
