// The fitting code on synthetic objectives with known optima (no rendering).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <tuple>

#include "shimmer/experiments/minimize.h"
#include "shimmer/experiments/fit_report.h"
#include "shimmer/experiments/fit_run.h"
#include "temp_dir.h"

namespace shimmer::experiments {
namespace {

// Deterministic "aliasing noise": a hash of p in [-1, 1].
double Noise(double p) {
  const double x = std::sin(p * 12.9898 * 437.0) * 43758.5453;
  return 2 * (x - std::floor(x)) - 1;
}

TEST(Fit, NoisyBowlFindsTheMinimum) {
  int calls = 0;
  auto j = [&](double p) {
    ++calls;
    const double d = std::log(p / 0.3);
    return d * d + 0.002 * Noise(p);
  };
  const Fit1D fit = Minimize1D(j, 0.01, 4, 7);
  EXPECT_NEAR(std::log(fit.best / 0.3), 0.0, 0.1) << fit.best;
  EXPECT_EQ(fit.evaluations, calls);
  EXPECT_EQ(int(fit.samples.size()), calls);
  for (const auto& [p, v] : fit.samples) {
    EXPECT_GE(p, 0.01 * (1 - 1e-12));
    EXPECT_LE(p, 4 * (1 + 1e-12));
    EXPECT_LE(fit.objective, v + 1e-15);
  }
}

TEST(Fit, PlateauStaysInBoundsAndNoWorseThanTheSweep) {
  // Flat above 0.5, rising below: any p >= 0.5 is optimal.
  auto j = [](double p) { return p < 0.5 ? std::log(0.5 / p) : 0.0; };
  const Fit1D fit = Minimize1D(j, 0.01, 4, 5, {1.0, 0.7});
  EXPECT_GE(fit.best, 0.5);
  EXPECT_LE(fit.best, 4.0);
  EXPECT_DOUBLE_EQ(fit.objective, 0.0);
}

TEST(Fit, OptimumAtTheBoundIsFound) {
  auto j = [](double p) { return p; };  // decreasing towards lo
  const Fit1D fit = Minimize1D(j, 0.05, 2, 6);
  EXPECT_NEAR(fit.best, 0.05, 1e-9);
}

// Joint fits: a known optimum between grid points, found by the refinement
// and not by the grid alone, with one logarithmic and one linear axis (2-D)
// and with three axes (3-D), on a bowl with aliasing noise.
TEST(FitND, FindsAKnownOptimumIn2D) {
  int calls = 0;
  auto j = [&](const std::vector<double>& p) {
    ++calls;
    const double a = std::log(p[0] / 0.3), b = (p[1] - 0.07) / 0.2;
    return 0.5 + a * a + b * b + 0.001 * Noise(p[0] + 3 * p[1]);
  };
  const std::vector<FitAxis> axes{{0.01, 4}, {-0.5, 0.5}};
  const FitND fit = MinimizeND(j, axes, 4);
  ASSERT_EQ(fit.best.size(), 2u);
  EXPECT_NEAR(std::log(fit.best[0] / 0.3), 0.0, 0.1) << fit.best[0];
  EXPECT_NEAR(fit.best[1], 0.07, 0.03) << fit.best[1];
  EXPECT_TRUE(fit.ceres_improved);
  EXPECT_EQ(fit.evaluations, calls);
  for (const auto& [p, v] : fit.samples) {
    for (std::size_t i = 0; i < 2; ++i) {
      EXPECT_GE(p[i], axes[i].lo - 1e-12);
      EXPECT_LE(p[i], axes[i].hi + 1e-12);
    }
    EXPECT_LE(fit.objective, v + 1e-15);
  }
}

TEST(FitND, FindsAKnownOptimumIn3DWithinTheBounds) {
  // Vlachos-like knobs: scale, bias, exponent; the bias optimum lies outside
  // its bounds, so the answer sits on that bound.
  auto j = [](const std::vector<double>& p) {
    const double s = std::log(p[0] / 2.0), b = (p[1] - 0.3) / 0.1, e = std::log(p[2] / 0.5);
    return 1 + s * s + b * b + 4 * e * e;
  };
  const std::vector<FitAxis> axes{{0.25, 8}, {-0.2, 0.2}, {0.1, 1}};
  const FitND fit = MinimizeND(j, axes, 3, {{1, 0, 0.333}});
  ASSERT_EQ(fit.best.size(), 3u);
  EXPECT_NEAR(std::log(fit.best[0] / 2.0), 0.0, 0.15) << fit.best[0];
  EXPECT_NEAR(fit.best[1], 0.2, 0.02) << fit.best[1];
  EXPECT_NEAR(std::log(fit.best[2] / 0.5), 0.0, 0.1) << fit.best[2];
  EXPECT_LT(fit.objective, 2.02);  // 1 + the bias term at its bound, ((0.2 - 0.3) / 0.1)^2
  EXPECT_LE(fit.evaluations, 27 + 1 + 6 * 19 + 1);  // grid, extra point, Ceres' iterations at 2N^2 + 1
}

TEST(FitND, OneAxisAgreesWithTheOneDimensionalSearch) {
  auto j1 = [](double p) { return std::pow(std::log(p / 0.8), 2); };
  auto jn = [&](const std::vector<double>& p) { return j1(p[0]); };
  const FitND nd = MinimizeND(jn, {{0.05, 4}}, 7);
  const Fit1D one = Minimize1D(j1, 0.05, 4, 7);
  EXPECT_NEAR(std::log(nd.best[0] / one.best), 0.0, 0.1);
}

// J's interval: each term's half-width scaled as J scales the term, summed
// in quadrature over shots and divided by their number.
TEST(Fit, ObjectiveHalfWidthPropagatesTheTermsIntervals) {
  ShotTerms t;
  t.flicker_none = 2, t.relmse_none = 4, t.bias = 0.1;
  t.flicker_hw = 0.2, t.relmse_hw = 0.4, t.bias_hw = 0.05;
  const FitWeights w{1, 2, 3};
  const double f = 0.2 / 2, e = 2 * 0.4 / 4, b = 3 * 2 * 0.1 * 0.05;
  EXPECT_NEAR(ObjectiveHalfWidth(w, {t}), std::sqrt(f * f + e * e + b * b), 1e-12);
  EXPECT_NEAR(ObjectiveHalfWidth(w, {t, t}), std::sqrt(2 * (f * f + e * e + b * b)) / 2, 1e-12);
  t.bias = 0;  // the bias term's width is its interval squared where b = 0
  EXPECT_NEAR(ObjectiveHalfWidth({0, 0, 1}, {t}), 0.05 * 0.05, 1e-15);
  EXPECT_EQ(ObjectiveHalfWidth(w, {}), 0);
}

TEST(Fit, ShotObjectiveIsNormalisedByTheUnfilteredShot) {
  ShotTerms t;
  t.flicker = 2e-6, t.flicker_none = 8e-6;  // a quarter of the flicker
  t.relmse = 0.3, t.relmse_none = 0.2;      // half again the spatial error
  t.bias = -0.2;
  EXPECT_NEAR(ShotObjective({1, 1, 1}, t), 0.25 + 1.5 + 0.04, 1e-12);
  EXPECT_NEAR(ShotObjective({2, 0, 10}, t), 0.5 + 0.4, 1e-12);
  // The same shot at a thousand times the brightness scores the same.
  ShotTerms bright = t;
  bright.flicker *= 1e6, bright.flicker_none *= 1e6;
  EXPECT_NEAR(ShotObjective({1, 1, 1}, bright), ShotObjective({1, 1, 1}, t), 1e-12);
  // Nothing to normalise by: the raw value counts.
  t.flicker_none = 0;
  EXPECT_NEAR(ShotObjective({1, 0, 0}, t), 2e-6, 1e-18);
}

TEST(Fit, PowerLawRecoversKnownCurveDespiteAnOutlier) {
  std::vector<double> alpha{0.01, 0.02, 0.05, 0.1, 0.2, 0.5}, value;
  for (double a : alpha) value.push_back(0.8 * std::pow(a, 0.6));
  value[3] *= 5;  // one odd material
  const PowerLaw law = FitPowerLaw(alpha, value);
  EXPECT_NEAR(law.a, 0.8, 0.08);
  EXPECT_NEAR(law.b, 0.6, 0.05);
  EXPECT_EQ(law.residuals.size(), alpha.size());
  EXPECT_GT(std::abs(law.residuals[3]), 1.0);  // the outlier stays an outlier
}

// Noise of known size on log values: the 95 % intervals of a and b hold the
// true coefficients; two points give a law but no interval.
TEST(Fit, PowerLawCoefficientsCarryIntervalsThatHoldTheTruth) {
  std::vector<double> alpha{0.01, 0.02, 0.05, 0.1, 0.2, 0.5}, value;
  const double wiggle[] = {0.05, -0.04, 0.03, -0.05, 0.04, -0.03};  // log units
  for (std::size_t i = 0; i < alpha.size(); ++i) value.push_back(0.8 * std::pow(alpha[i], 0.6) * std::exp(wiggle[i]));
  const PowerLaw law = FitPowerLaw(alpha, value);
  ASSERT_TRUE(law.HasInterval());
  EXPECT_LT(law.a_lo, 0.8);
  EXPECT_GT(law.a_hi, 0.8);
  EXPECT_LT(law.b_lo, 0.6);
  EXPECT_GT(law.b_hi, 0.6);
  EXPECT_LT(law.b_hi - law.b_lo, 0.1);  // tight: the noise is 5 % over 1.7 decades of alpha
  EXPECT_LT(law.a_lo, law.a);
  EXPECT_GT(law.a_hi, law.a);
  const PowerLaw two = FitPowerLaw({0.01, 0.1}, {0.02, 0.06});
  EXPECT_FALSE(two.HasInterval());
  EXPECT_NEAR(two.b, std::log(3.0) / std::log(10.0), 1e-6);
}

TEST(Fit, ValuesOnABoundAreMarkedAndLeftOutOfTheLaw) {
  EXPECT_EQ(OnBound(0.01, {0.01, 4}), Bound::kLower);
  EXPECT_EQ(OnBound(4, {0.01, 4}), Bound::kUpper);
  EXPECT_EQ(OnBound(3.99, {0.01, 4}), Bound::kUpper);  // within 0.1 % of the log span
  EXPECT_EQ(OnBound(3.9, {0.01, 4}), Bound::kInside);
  EXPECT_EQ(OnBound(-0.5, {-0.5, 0.5}), Bound::kLower);  // linear axes: of the span itself
  EXPECT_EQ(OnBound(0, {-0.5, 0.5}), Bound::kInside);
  std::vector<MaterialFit> fits;
  for (auto [material, alpha, value] : {std::tuple<const char*, double, double>{"ggx:0.01", 0.01, 0.02},
                                        {"ggx:0.05", 0.05, 0.05},
                                        {"ggx:0.2", 0.2, 0.11},
                                        {"ggx:0.5", 0.5, 4.0}}) {
    MaterialFit f;
    f.variant = "k16-beckmann-rect", f.param = "fp_max", f.ndf = "ggx", f.material = material;
    f.alpha = alpha, f.lo = 0.01, f.hi = 4, f.search.best = value;
    fits.push_back(f);
  }
  const std::vector<FitLaw> laws = FitLaws(fits);
  ASSERT_EQ(laws.size(), 1u);
  EXPECT_EQ(laws[0].materials, (std::vector<std::string>{"ggx:0.01", "ggx:0.05", "ggx:0.2"}));
  EXPECT_EQ(laws[0].on_bound, (std::vector<std::string>{"ggx:0.5"}));
}

// fit.md from fits with known numbers: bound notes, verdicts only where
// the J intervals are apart, the law with its coefficients' intervals; and
// the same report again from the fit.json it wrote.
TEST(FitJson, ReportMarksBoundsDecidesByIntervalsAndRewritesFromItsJson) {
  std::vector<MaterialFit> fits;
  auto add = [&](const char* material, double alpha, double value, double j_validate, double j_default) {
    MaterialFit f;
    f.variant = "k16-beckmann-rect", f.param = "fp_max", f.ndf = "ggx", f.material = material;
    f.alpha = alpha, f.lo = 0.01, f.hi = 4, f.search.best = value;
    f.search.samples = {{0.01, 2}, {value, 1}, {4, 3}};
    f.search.evaluations = 3;
    f.train = {1, 0.1, {}};
    f.validate = {j_validate, 0.1, {}};
    f.defaults = {1.0};
    f.train_defaults = {{1.2, 0.1, {}}};
    f.validate_defaults = {{j_default, 0.1, {}}};
    fits.push_back(f);
  };
  add("ggx:0.01", 0.01, 0.02, 1.0, 2.0);    // apart: beats the default
  add("ggx:0.05", 0.05, 0.05, 1.0, 1.05);   // overlapping: tied, although lower
  add("ggx:0.1", 0.1, 0.07, 3.0, 1.0);      // apart: loses
  add("ggx:0.2", 0.2, 0.11, 1.0, 1.0);      // tied
  add("ggx:0.5", 0.5, 4.0, 1.0, 1.0);       // on the upper bound
  FitOutcome outcome;
  outcome.fits = fits;
  outcome.laws = FitLaws(fits);
  Spec spec;
  spec.name = "t";
  shimmer::testing::TempDir dir;
  ASSERT_TRUE(WriteFitReport(outcome, spec, (dir.path() / "a").string(), nullptr));
  std::ifstream in(dir.path() / "a" / "fit.md");
  const std::string md((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(md.find("**4** (on its upper bound 4)"), std::string::npos) << md;
  EXPECT_NE(md.find("the fitted value for ggx:0.01 (J 1 ± 0.1) beats the default 1"), std::string::npos) << md;
  EXPECT_NE(md.find("the fitted value for ggx:0.1 (J 3 ± 0.1) loses to the default 1"), std::string::npos) << md;
  EXPECT_EQ(md.find("the fitted value for ggx:0.05 "), std::string::npos) << md;
  EXPECT_NE(md.find("3 of 5 held-out comparisons with a default are tied"), std::string::npos) << md;
  EXPECT_NE(md.find("1 of 5 fitted values sit on a bound"), std::string::npos) << md;
  EXPECT_NE(md.find("Left out, their fitted value on a bound: ggx:0.5."), std::string::npos) << md;
  EXPECT_NE(md.find(", a in ["), std::string::npos) << md;
  EXPECT_NE(md.find("degrees of freedom"), std::string::npos) << md;
  // Again from its fit.json: the same fit.md.
  const auto read = ReadFitOutcome((dir.path() / "a" / "fit.json").string());
  ASSERT_TRUE(read) << read.error();
  ASSERT_EQ(read->fits.size(), 5u);
  EXPECT_EQ(read->fits[0].search.samples, fits[0].search.samples);
  EXPECT_EQ(read->laws.size(), 1u);
  ASSERT_TRUE(WriteFitReport(*read, spec, (dir.path() / "b").string(), nullptr));
  std::ifstream again(dir.path() / "b" / "fit.md");
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(again)), {}), md);
}

// fit.json's joint fits read back as WriteFitReport wrote them (JointFit::ToJson).
TEST(FitJson, JointFitsReadBackAsWritten) {
  JointFit f;
  f.variant = "godot", f.material = "ggx:0.1", f.ndf = "ggx", f.alpha = 0.1;
  f.params = {"sigma2", "kappa"};
  f.search.best = {0.2076, 0.9048};
  f.defaults = {0.25, 0.18};
  f.train = {0.56, 0.24, {}};
  f.validate = {0.67, 0.21, {}};
  f.train_defaults = {0.6, 0.23, {}};
  f.validate_defaults = {0.671, 0.2, {}};
  f.folds.push_back({"wires", true, {0.3, 0.5}, {0.1, 0.08, {}}, {0.14, 0.09, {}}});
  shimmer::testing::TempDir dir;
  const auto path = dir.path() / "fit.json";
  std::ofstream(path) << nlohmann::json{{"fits", nlohmann::json::array()}, {"joint_fits", {f.ToJson()}}}.dump(2);
  const auto read = ReadJointFits(path.string());
  ASSERT_TRUE(read) << read.error();
  ASSERT_EQ(read->size(), 1u);
  const JointFit& g = read->front();
  EXPECT_EQ(g.variant, "godot");
  EXPECT_EQ(g.material, "ggx:0.1");
  EXPECT_EQ(g.params, f.params);
  EXPECT_EQ(g.search.best, f.search.best);
  EXPECT_EQ(g.defaults, f.defaults);
  EXPECT_DOUBLE_EQ(g.validate.j, 0.67);
  EXPECT_DOUBLE_EQ(g.validate_defaults.half_width, 0.2);
  ASSERT_EQ(g.folds.size(), 1u);
  EXPECT_EQ(g.folds[0].scene, "wires");
  EXPECT_DOUBLE_EQ(g.folds[0].held_out_defaults.j, 0.14);
  // The engine-settings table: Godot's knobs under its own names.
  const auto rows = EngineSettingRows(*read);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].fitted, "roughness_limiter_amount = 0.2076, roughness_limiter_limit = 0.9048");
  EXPECT_EQ(rows[0].held_out, "tied (intervals overlap)");
}

TEST(FitJson, BadFilesGetOneErrorNamingThem) {
  shimmer::testing::TempDir dir;
  auto write = [&](const char* name, const std::string& text) {
    std::ofstream(dir.path() / name) << text;
    return (dir.path() / name).string();
  };
  const std::string cases[][2] = {
      {write("none.json", "{\"fits\": []}"), "no \"joint_fits\""},
      {write("empty.json", "{\"joint_fits\": []}"), "has no joint fits"},
      {write("short.json", "{\"joint_fits\": [{\"variant\": \"godot\"}]}"), "not a fit.json as shimmer fit writes it"},
      {write("broken.json", "{\"joint_fits\": ["), "broken.json"},
      {(dir.path() / "missing.json").string(), "missing.json"},
  };
  for (const auto& [path, why] : cases) {
    const auto read = ReadJointFits(path);
    ASSERT_FALSE(read) << path;
    EXPECT_NE(read.error().find(why), std::string::npos) << read.error();
    EXPECT_NE(read.error().find(std::filesystem::path(path).filename().string()), std::string::npos) << read.error();
  }
}

}  // namespace
}  // namespace shimmer::experiments
