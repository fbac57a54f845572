// The fitting code on synthetic objectives with known optima (no rendering).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

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
