// Normal maps in the shading core (normal_map.glsl, scene.glsl), in double on
// the CPU: uv and tangent frames of each primitive, the mip-chain sampler,
// and the normal-map filters' known answers.
#include <gtest/gtest.h>

#include <cmath>

#include "../shading/quadrature.h"
#include "shimmer/renderer/normal_map.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"

namespace shimmer::scene {
namespace {

constexpr double kPi = 3.14159265358979323846;
// NMF_* of normal_map.glsl.
constexpr int kNone = 0, kPoint = 1, kMip = 2, kToksvig = 3, kToksvigBp = 4, kToksvigMap = 5, kLean = 6, kClean = 7,
              kVmf = 8, kHdrp = 9;

std::shared_ptr<const NormalMap> ConstantMap(glm::dvec3 n, int size = 4) {
  auto map = BuildNormalMap("constant", size, size, std::vector<glm::dvec3>(std::size_t(size * size), n));
  EXPECT_TRUE(map) << map.error();
  return std::make_shared<const NormalMap>(std::move(*map));
}

std::shared_ptr<const NormalMap> Procedural(const std::string& name) {
  NormalMapSource src;
  src.procedural = name;
  auto map = LoadNormalMap(src);
  EXPECT_TRUE(map) << map.error();
  return *map;
}

Scene OneMappedPrimitive(Primitive::Type type, std::shared_ptr<const NormalMap> map, glm::dvec2 scale = {1, 1}) {
  Scene s;
  Primitive p;
  p.type = type;
  p.a = {0.2, -0.1, 0.3};
  p.b = {1.4, 0.5, -0.2};
  p.radius = type == Primitive::Type::kPlane ? 0.0 : 0.7;
  p.normal_map = std::move(map);
  p.normal_map_scale = scale;
  s.primitives.push_back(p);
  return s;
}

// Points on each primitive's surface, away from poles and seams.
std::vector<glm::dvec3> SurfacePoints(const Primitive& p) {
  std::vector<glm::dvec3> out;
  for (int i = 0; i < 12; ++i) {
    const double a = 0.3 + 0.5 * i, h = -0.8 + 0.13 * i;
    if (p.type == Primitive::Type::kPlane) out.push_back({std::cos(a) * 3, p.radius, std::sin(a) * 2});
    if (p.type == Primitive::Type::kSphere) {
      const double r = std::sqrt(1 - h * h);
      out.push_back(p.a + p.radius * glm::dvec3(r * std::cos(a), h, r * std::sin(a)));
    }
    if (p.type == Primitive::Type::kCapsule) {
      const glm::dvec3 u = glm::normalize(p.b - p.a);
      const glm::dvec3 e1 = glm::normalize(glm::cross(u, glm::dvec3(1, 0, 0)));
      const glm::dvec3 e2 = glm::cross(u, e1);
      const double along = (0.1 + 0.07 * i) * glm::length(p.b - p.a);
      out.push_back(p.a + u * along + p.radius * (e1 * std::cos(a) + e2 * std::sin(a)));
    }
  }
  return out;
}

TEST(NormalMapShading, TangentFramesAreOrthonormalAndUvGradientsMatchTheirDifferences) {
  for (auto type : {Primitive::Type::kPlane, Primitive::Type::kSphere, Primitive::Type::kCapsule}) {
    const Scene s = OneMappedPrimitive(type, ConstantMap({0, 0, 1}));
    const auto words = PackScene(s);
    for (const glm::dvec3& p : SurfacePoints(s.primitives[0])) {
      SCOPED_TRACE(int(type));
      const auto f = shading::SurfaceUvFrameAt(words, 0, p);
      EXPECT_NEAR(glm::length(f.t), 1, 1e-12);
      EXPECT_NEAR(glm::length(f.b), 1, 1e-12);
      EXPECT_NEAR(glm::length(f.n), 1, 1e-12);
      EXPECT_NEAR(glm::dot(f.t, f.b), 0, 1e-12);
      EXPECT_NEAR(glm::dot(f.t, f.n), 0, 1e-12);
      EXPECT_NEAR(glm::dot(glm::cross(f.t, f.b), f.n), 1, 1e-12);  // right-handed
      // The frame is continuous and uv's gradient is its derivative: a small
      // step along t and b (projected back onto the surface by the frame at
      // the next point) changes uv by the gradient times the step.
      for (const glm::dvec3 dir : {f.t, f.b}) {
        const double h = 1e-5;
        glm::dvec3 q = p + dir * h;
        if (type == Primitive::Type::kSphere) q = s.primitives[0].a + glm::normalize(q - s.primitives[0].a) * 0.7;
        const auto g = shading::SurfaceUvFrameAt(words, 0, q);
        EXPECT_LT(glm::length(g.t - f.t), 1e-3);
        EXPECT_LT(glm::length(g.n - f.n), 1e-3);
        const glm::dvec2 duv = g.uv - f.uv;
        EXPECT_NEAR(duv.x, glm::dot(f.du, q - p), 1e-3 * h + 1e-10);
        EXPECT_NEAR(duv.y, glm::dot(f.dv, q - p), 1e-3 * h + 1e-10);
      }
      // u and v grow along t and b, so a tangent-space normal reads the same
      // on every primitive.
      EXPECT_GT(glm::dot(f.du, f.t), 0);
      EXPECT_GT(glm::dot(f.dv, f.b), 0);
    }
  }
}

TEST(NormalMapShading, AFlatMapRendersTheUnmappedSurfaceAndATiltedOneTiltsTheNormal) {
  shading::CameraDesc cam;
  cam.pos = {0, 0.5, 4};
  cam.fwd = glm::normalize(glm::dvec3(0, -0.1, -1));
  cam.right = {1, 0, 0};
  cam.up = glm::cross(cam.right, cam.fwd);
  cam.width = cam.height = 24;
  shading::LightDesc light;
  light.vec = glm::normalize(glm::dvec3(0.2, 0.7, 0.6));
  shading::MaterialDesc m;
  m.alpha = {0.2, 0.2};
  for (auto type : {Primitive::Type::kSphere, Primitive::Type::kCapsule, Primitive::Type::kPlane}) {
    Scene flat = OneMappedPrimitive(type, ConstantMap({0, 0, 1}));
    Scene bare = flat;
    bare.primitives[0].normal_map = nullptr;
    Scene tilted = OneMappedPrimitive(type, ConstantMap({0.3, 0, 1}));
    const auto wf = PackScene(flat), wb = PackScene(bare), wt = PackScene(tilted);
    int hits = 0;
    for (int y = 0; y < 24; y += 3)
      for (int x = 0; x < 24; x += 3)
        for (auto d : {shading::DerivativeSource::kQuadFine, shading::DerivativeSource::kAnalytic}) {
          const auto a = shading::ShadePixel(wf, cam, light, m, 0, d, {}, {x, y});
          const auto b = shading::ShadePixel(wb, cam, light, m, 0, d, {}, {x, y});
          ASSERT_EQ(a.hit, b.hit);
          if (!a.hit) continue;
          ++hits;
          EXPECT_NEAR(glm::length(a.normal - b.normal), 0, 1e-12);
          EXPECT_NEAR(a.specular.y, b.specular.y, 1e-12 * (1 + b.specular.y));
          EXPECT_NEAR(a.diffuse.y, b.diffuse.y, 1e-12 * (1 + b.diffuse.y));
          const auto t = shading::ShadePixel(wt, cam, light, m, 0, d, {}, {x, y});
          // The tilted map turns the normal towards its frame's tangent by atan(0.3).
          EXPECT_NEAR(std::acos(std::clamp(glm::dot(t.normal, b.normal), -1.0, 1.0)), std::atan(0.3), 1e-6);  // texels are float
        }
    EXPECT_GT(hits, 10) << int(type);
  }
}

TEST(NormalMapShading, TheSamplerReadsLevelZeroUpCloseAndTheMapMeanFarAway) {
  const auto map = Procedural("bumps");
  const Scene s = OneMappedPrimitive(Primitive::Type::kPlane, map);
  const auto words = PackScene(s);
  const NormalMapTexel& mean = map->levels.back().texels[0];
  const glm::dvec2 uv{0.3172, 0.6491};
  // No footprint: the filtered read is level 0, bilinear, as kNone reads it.
  const auto l0 = shading::ReadNormalMap(words, 0, kNone, uv, {0, 0}, {0, 0});
  const auto f0 = shading::ReadNormalMap(words, 0, kToksvig, uv, {0, 0}, {0, 0});
  EXPECT_NEAR(glm::length(glm::dvec3(l0.mean_normal_ft) - glm::dvec3(f0.mean_normal_ft)), 0, 1e-7);
  EXPECT_NEAR(glm::length(l0.b - f0.b), 0, 1e-7);
  // A footprint of several map widths: the 1x1 level, the map's mean.
  const auto far = shading::ReadNormalMap(words, 0, kToksvig, uv, {3, 0}, {0, 3});
  EXPECT_NEAR(glm::length(glm::dvec3(far.mean_normal_ft) - glm::dvec3(mean.mean_normal)), 0, 1e-6);
  EXPECT_NEAR(far.m.x, mean.m.x, 1e-6);
  EXPECT_LT(glm::length(glm::dvec3(far.mean_normal_ft)), 0.999);  // the bumps spread the normals
  // Point sampling is the nearest texel's normal, not a blend.
  const NormalMapLevel& top = map->levels[0];
  const glm::dvec2 centre{(37 + 0.5) / top.width, (101 + 0.5) / top.height};
  const auto p = shading::ReadNormalMap(words, 0, kPoint, centre + glm::dvec2(0.4 / top.width, -0.4 / top.height),
                                        {0, 0}, {0, 0});
  EXPECT_NEAR(glm::length(glm::dvec3(p.mean_normal_ft) - glm::dvec3(top.texels[101 * top.width + 37].mean_normal)),
              0, 1e-7);
  // Anisotropy: a footprint 8 texels long and 1 wide reads a finer level
  // than an isotropic one of 8 texels, so it keeps more of the spread.
  const double texel = 1.0 / top.width;
  double aniso = 0, iso = 0;
  for (int i = 0; i < 16; ++i) {
    const glm::dvec2 at{0.061 * i, 0.037 * i};
    const auto a = shading::ReadNormalMap(words, 0, kToksvig, at, {8 * texel, 0}, {0, texel});
    const auto b = shading::ReadNormalMap(words, 0, kToksvig, at, {8 * texel, 0}, {0, 8 * texel});
    aniso += glm::length(glm::dvec3(a.mean_normal_ft));
    iso += glm::length(glm::dvec3(b.mean_normal_ft));
  }
  EXPECT_GT(aniso, iso);
}

// Box means of normals whose slopes are Gaussian-like with variance s2 per
// axis (a deterministic grid of slopes): what a deep mip level holds.
shading::NormalMapRead Spread(double s2x, double s2y) {
  glm::dvec3 n{0}, m{0};
  glm::dvec2 b{0};
  int count = 0;
  for (int i = -20; i <= 20; ++i)
    for (int j = -20; j <= 20; ++j) {
      // Points of a 41x41 grid mapped through a smooth inverse-CDF-like
      // spread: slope = sqrt(2 s2) erfinv-ish; a uniform grid of standard
      // deviation 1 is enough: variance is what the filters read.
      const double u = i / 20.0 * std::sqrt(3.0), v = j / 20.0 * std::sqrt(3.0);
      const glm::dvec2 t{u * std::sqrt(s2x), v * std::sqrt(s2y)};
      const glm::dvec3 nn = glm::normalize(glm::dvec3(t, 1));
      n += nn;
      b += t;
      m += glm::dvec3(t.x * t.x, t.y * t.y, t.x * t.y);
      ++count;
    }
  return {glm::dvec4(n / double(count), 1), b / double(count), m / double(count)};
}

TEST(NormalMapFilters, IsotropicSpreadWidensAlphaSquaredByTwiceTheSlopeVariance) {
  const glm::dvec2 alpha{0.05, 0.05};
  for (double s2 : {1e-4, 1e-3, 4e-3}) {
    SCOPED_TRACE(s2);
    const auto r = Spread(s2, s2);
    // E[t^2] of the grid is s2 * (1 + 1/20)...: take the exact variance.
    const double var = r.m.x - r.b.x * r.b.x;
    const double want = alpha.x * alpha.x + 2 * var;
    for (int nmf : {kToksvig, kToksvigBp, kLean, kClean, kVmf}) {
      const glm::dvec2 a = shading::NormalMapFilterAlpha(nmf, r, alpha);
      EXPECT_NEAR(a.x * a.x, want, 0.08 * (want - alpha.x * alpha.x)) << nmf;
      EXPECT_NEAR(a.x, a.y, 1e-12) << nmf;
    }
    // HDRP's 0.25 / kappa variance widens a quarter as much as vMF's 1 / kappa
    // (below its cap).
    const glm::dvec2 h = shading::NormalMapFilterAlpha(kHdrp, r, alpha);
    const glm::dvec2 v = shading::NormalMapFilterAlpha(kVmf, r, alpha);
    EXPECT_NEAR(h.x * h.x - alpha.x * alpha.x, std::min(0.25 * (v.x * v.x - alpha.x * alpha.x), 2 * 0.03125), 1e-12);
    // The baselines keep the material's roughness.
    for (int nmf : {kNone, kPoint, kMip}) EXPECT_EQ(shading::NormalMapFilterAlpha(nmf, r, alpha), alpha);
  }
}

// nm_scale scales the added alpha^2: 0 keeps the material, 2 doubles the widening.
TEST(NormalMapFilters, NmScaleScalesTheAddedVariance) {
  const auto r = Spread(2e-3, 1e-3);
  const glm::dvec2 alpha{0.05, 0.08};
  for (int nmf : {kToksvig, kToksvigMap, kLean, kClean, kVmf, kHdrp}) {
    const glm::dvec2 one = shading::NormalMapFilterAlpha(nmf, r, alpha, 1);
    const glm::dvec2 zero = shading::NormalMapFilterAlpha(nmf, r, alpha, 0);
    const glm::dvec2 two = shading::NormalMapFilterAlpha(nmf, r, alpha, 2);
    EXPECT_NEAR(glm::length(zero - alpha), 0, 1e-12) << nmf;
    for (int i = 0; i < 2; ++i)
      EXPECT_NEAR(two[i] * two[i] - alpha[i] * alpha[i], 2 * (one[i] * one[i] - alpha[i] * alpha[i]), 1e-12) << nmf;
  }
}

TEST(NormalMapFilters, LeanIsAnisotropicWhereTheSlopesAreAndCleanIsNot) {
  const auto r = Spread(4e-3, 1e-4);
  const glm::dvec2 alpha{0.05, 0.05};
  const glm::dvec2 lean = shading::NormalMapFilterAlpha(kLean, r, alpha);
  const glm::dvec2 clean = shading::NormalMapFilterAlpha(kClean, r, alpha);
  EXPECT_GT(lean.x, 2 * lean.y);
  EXPECT_NEAR(clean.x, clean.y, 1e-12);
  // CLEAN keeps LEAN's total variance.
  EXPECT_NEAR(clean.x * clean.x + clean.y * clean.y, lean.x * lean.x + lean.y * lean.y, 1e-12);
}

// LEAN with its whole covariance: ridges at an angle to the tangent give a
// lobe turned to them, and the turned lobe is exactly diag(alpha^2) + 2 Sigma.
TEST(NormalMapFilters, LeanTurnsItsLobeToTheRidges) {
  for (double theta : {0.0, 0.4, kPi / 4, 1.2, -0.7}) {
    SCOPED_TRACE(theta);
    // Slopes spread along direction theta (variance 4e-3) and across it (2e-4).
    const double c = std::cos(theta), s = std::sin(theta);
    const double va = 4e-3, vb = 2e-4;
    const double sxx = va * c * c + vb * s * s, syy = va * s * s + vb * c * c, sxy = (va - vb) * c * s;
    const shading::NormalMapRead r{glm::dvec4(0, 0, 1, 1), {0.01, -0.02},
                                   {sxx + 1e-4, syy + 4e-4, sxy + 0.01 * -0.02}};
    const glm::dvec2 alpha{0.05, 0.03};
    const auto lobe = shading::NormalMapLobe(kLean, r, alpha);
    // Back from the turned axes: R = Q diag(a^2) Q^T.
    const double qc = std::cos(lobe.angle), qs = std::sin(lobe.angle);
    const double a1 = lobe.alpha.x * lobe.alpha.x, a2 = lobe.alpha.y * lobe.alpha.y;
    EXPECT_NEAR(a1 * qc * qc + a2 * qs * qs, alpha.x * alpha.x + 2 * sxx, 1e-12);
    EXPECT_NEAR(a1 * qs * qs + a2 * qc * qc, alpha.y * alpha.y + 2 * syy, 1e-12);
    EXPECT_NEAR((a1 - a2) * qc * qs, 2 * sxy, 1e-12);
    // The turn stays within 45 degrees (continuous across pixels); the long
    // axis runs along the ridges' slope direction (up to the material's own
    // anisotropy).
    EXPECT_LE(std::abs(lobe.angle), kPi / 4 + 1e-12);
    const double long_axis = lobe.alpha.x >= lobe.alpha.y ? lobe.angle : lobe.angle + kPi / 2;
    EXPECT_GT(std::abs(std::cos(long_axis - theta)), 0.99);
    // The other filters keep the tangent frame.
    EXPECT_EQ(shading::NormalMapLobe(kToksvig, r, alpha).angle, 0.0);
  }
}

TEST(NormalMapFilters, LeanAndCleanShadeWithTheMeanSlopesNormal) {
  shading::NormalMapRead r = Spread(1e-3, 1e-3);
  r.b = {0.2, -0.1};
  const glm::dvec3 n = shading::NormalMapFilterNormal(kLean, r);
  EXPECT_NEAR(n.x / n.z, 0.2, 1e-12);
  EXPECT_NEAR(n.y / n.z, -0.1, 1e-12);
  EXPECT_NEAR(glm::length(shading::NormalMapFilterNormal(kClean, r) - n), 0, 1e-12);
  EXPECT_NEAR(glm::length(shading::NormalMapFilterNormal(kMip, r) - glm::normalize(glm::dvec3(r.mean_normal_ft))), 0,
              1e-12);
}

// Seed 003's conversion of a Toksvig map baked at power 100 to the material's
// power s, ft /= lerp(s / 100, 1, ft), is exact: it gives the factor computed
// at power s from the same mean normal length.
TEST(NormalMapFilters, TheToksvigMapConvertsExactlyFromItsFixedPower) {
  for (double len : {0.999, 0.99, 0.95, 0.8}) {
    shading::NormalMapRead r{glm::dvec4(0, 0, len, 0), {0, 0}, {0, 0, 0}};
    r.mean_normal_ft.w = len / (len + kToksvigFixedPower * (1 - len));
    for (double alpha : {0.02, 0.05, 0.2, 0.6}) {
      const glm::dvec2 map = shading::NormalMapFilterAlpha(kToksvigMap, r, {alpha, alpha});
      const glm::dvec2 bp = shading::NormalMapFilterAlpha(kToksvigBp, r, {alpha, alpha});
      EXPECT_NEAR(map.x, bp.x, 1e-9 * bp.x) << len << " " << alpha;
      EXPECT_GE(map.x, alpha);
    }
  }
}

TEST(NormalMapFilters, NoNanOrShrinkForDegenerateStatistics) {
  const shading::NormalMapRead cases[] = {
      {glm::dvec4(0, 0, 1, 1), {0, 0}, {0, 0, 0}},            // flat
      {glm::dvec4(0, 0, 0, 0), {0, 0}, {0, 0, 0}},            // normals cancel
      {glm::dvec4(0, 0, 1e-9, 1e-9), {0, 0}, {1e9, 1e9, 0}},  // huge slopes
      {glm::dvec4(0.5, 0, 0.5, 0.5), {1e3, 0}, {1, 0, 0}},    // M below B B^T (inconsistent input)
  };
  for (const auto& r : cases)
    for (int nmf = kNone; nmf <= kHdrp; ++nmf)
      for (double alpha : {1e-4, 0.05, 1.0}) {
        const glm::dvec2 a = shading::NormalMapFilterAlpha(nmf, r, {alpha, alpha});
        EXPECT_TRUE(std::isfinite(a.x) && std::isfinite(a.y)) << nmf;
        EXPECT_GE(a.x, alpha * (1 - 1e-12)) << nmf;
        EXPECT_LE(a.x, std::max(alpha, 1.0) * (1 + 1e-12)) << nmf;
        const glm::dvec3 n = shading::NormalMapFilterNormal(nmf, r);
        EXPECT_NEAR(glm::length(n), 1, 1e-9) << nmf;
      }
}

// A map of two normals in a checkerboard: every 2x2 mean is their average,
// and the filters' spread follows from its length in closed form.
TEST(NormalMapFilters, TwoKnownNormalsGiveTheirMeanAndToksvigsSigma) {
  const glm::dvec3 n1 = glm::normalize(glm::dvec3(0.3, 0.1, 1)), n2 = glm::normalize(glm::dvec3(-0.2, 0.25, 1));
  std::vector<glm::dvec3> texels;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) texels.push_back((x + y) % 2 ? n2 : n1);
  auto map = BuildNormalMap("two", 8, 8, texels);
  ASSERT_TRUE(map) << map.error();
  const glm::dvec3 mean = (n1 + n2) * 0.5;
  for (std::size_t l = 1; l < map->levels.size(); ++l)
    for (const NormalMapTexel& t : map->levels[l].texels)
      EXPECT_NEAR(glm::length(glm::dvec3(t.mean_normal) - mean), 0, 1e-6) << l;
  const NormalMapTexel& top = map->levels.back().texels[0];
  const shading::NormalMapRead r{glm::dvec4(glm::dvec3(top.mean_normal), top.toksvig_ft), glm::dvec2(top.b),
                                 glm::dvec3(top.m)};
  const double len = glm::length(mean), sigma2 = (1 - len) / len;
  const glm::dvec2 a = shading::NormalMapFilterAlpha(kToksvig, r, {0.05, 0.05});
  EXPECT_NEAR(a.x * a.x, 0.0025 + 2 * sigma2, 1e-6);
  // LEAN's covariance of two equally likely slopes t1, t2: (t1 - t2)(t1 - t2)^T / 4.
  const glm::dvec2 t1{n1.x / n1.z, n1.y / n1.z}, t2{n2.x / n2.z, n2.y / n2.z};
  const glm::dvec2 lean = shading::NormalMapFilterAlpha(kLean, r, {0.05, 0.05});
  EXPECT_NEAR(lean.x * lean.x, 0.0025 + 2 * (t1.x - t2.x) * (t1.x - t2.x) / 4, 1e-6);
  EXPECT_NEAR(lean.y * lean.y, 0.0025 + 2 * (t1.y - t2.y) * (t1.y - t2.y) / 4, 1e-6);
  EXPECT_NEAR(top.m.z - top.b.x * top.b.y, (t1.x - t2.x) * (t1.y - t2.y) / 4, 1e-6);
}

// LEAN's moments of h = A sin(2 pi k u) over the tile: t.x = -2 pi k A cos(..)
// per uv unit, so E[t.x] = 0, E[t.x^2] = (2 pi k A)^2 / 2 (exact for a sampled
// sinusoid of integer frequency), t.y = 0.
TEST(NormalMapFilters, LeanMomentsOfASineBumpMatchTheClosedForm) {
  const int n = 64, k = 3;
  const double amp = 0.01;
  std::vector<glm::dvec3> texels;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double u = (x + 0.5) / n;
      const double slope = -2 * kPi * k * amp * std::cos(2 * kPi * k * u);
      texels.push_back(glm::normalize(glm::dvec3(slope, 0, 1)));
    }
  auto map = BuildNormalMap("sine", n, n, texels);
  ASSERT_TRUE(map) << map.error();
  const NormalMapTexel& top = map->levels.back().texels[0];
  const double g = 2 * kPi * k * amp;
  EXPECT_NEAR(top.b.x, 0, 1e-7);
  EXPECT_NEAR(top.m.x, g * g / 2, 1e-6 * g * g);
  EXPECT_NEAR(top.m.y, 0, 1e-9);
  EXPECT_NEAR(top.m.z, 0, 1e-9);
}

// The vMF fit's kappa from the mean normal length r against the definition:
// a vMF of concentration kappa has r = coth(kappa) - 1/kappa; vmf widens
// alpha^2 by 2 / kappa. Banerjee's approximation is within a few per cent.
TEST(NormalMapFilters, VmfKappaFromTheMeanLengthMatchesItsDefinition) {
  for (double kappa : {2.0, 5.0, 20.0, 100.0, 1e3, 1e4}) {
    const double r = 1 / std::tanh(kappa) - 1 / kappa;
    const shading::NormalMapRead read{glm::dvec4(0, 0, r, 1), {0, 0}, {0, 0, 0}};
    const glm::dvec2 a = shading::NormalMapFilterAlpha(kVmf, read, {0.01, 0.01});
    const double add = a.x * a.x - 1e-4;
    EXPECT_NEAR(add, std::min(2 / kappa, 1 - 1e-4), 0.05 * 2 / kappa) << kappa;
  }
}

// Every normal-map filter changes only the normal and alpha; the NDF it then
// evaluates stays normalised: the integral of the slope density is 1.
TEST(NormalMapFilters, WidenedNdfsStayNormalised) {
  const auto r = Spread(3e-3, 5e-4);
  for (auto ndf : {shading::Ndf::kGgx, shading::Ndf::kBeckmann})
    for (int nmf = kNone; nmf <= kHdrp; ++nmf) {
      const glm::dvec2 a = shading::NormalMapFilterAlpha(nmf, r, {0.02, 0.03});
      auto over_theta = [&](double phi) {
        return test::Integrate(
            [&](double theta) {
              const double t = std::tan(theta);
              const glm::dvec2 slope{t * std::cos(phi), t * std::sin(phi)};
              return shading::SlopeDensity<double>(ndf, slope, a) * t / (std::cos(theta) * std::cos(theta));
            },
            0, kPi / 2, {std::atan(a.x), std::atan(3 * a.x), std::atan(30 * a.x)}, 1e-9, 1e-13, 40);
      };
      const double integral = test::Integrate(over_theta, 0, 2 * kPi, {kPi / 2, kPi, 1.5 * kPi}, 1e-7, 1e-10, 8);
      EXPECT_NEAR(integral, 1, 1e-3) << nmf << " " << int(ndf);
    }
}

// Texture hardware's level: an isotropic footprint of 2^k texels reads level
// k exactly (bilinear there).
TEST(NormalMapShading, AnIsotropicFootprintOfTwoToTheKTexelsReadsLevelK) {
  const auto map = Procedural("bumps");
  const Scene s = OneMappedPrimitive(Primitive::Type::kPlane, map);
  const auto words = PackScene(s);
  const double texel = 1.0 / map->levels[0].width;
  for (int k = 1; k < 6; ++k) {
    const double f = texel * (1 << k);
    // At a texel centre of level k the bilinear read is that texel.
    const int side = map->levels[std::size_t(k)].width;
    const glm::dvec2 uv{(5 + 0.5) / side, (6 + 0.5) / side};
    const auto read = shading::ReadNormalMap(words, 0, kToksvig, uv, {f, 0}, {0, f});
    const NormalMapTexel& want = map->levels[std::size_t(k)].texels[std::size_t(6 * side + 5)];
    EXPECT_NEAR(glm::length(glm::dvec3(read.mean_normal_ft) - glm::dvec3(want.mean_normal)), 0, 1e-6) << k;
    EXPECT_NEAR(read.m.x, want.m.x, 1e-6) << k;
  }
}

// GEOMETRIC+NORMALMAP: the normal-map filter's roughness is the geometric
// filter's input, so the widenings add in alpha^2: tk19+toksvig is tk19's
// kernel (on the filtered normals' spread) added to toksvig's alpha^2.
TEST(NormalMapShading, CombinationsAddTheGeometricKernelToTheNormalMapsAlphaSquared) {
  const Scene s = LoadScene("nm-plane").value();
  const auto words = PackScene(s);
  const shading::CameraDesc cam = CameraAt(CameraPath::kOrbit, s.rig, 0, 30, 48, 48);
  const int toksvig = shading::FindVariant("toksvig")->id, combo = shading::FindVariant("tk19+toksvig")->id;
  ASSERT_EQ(combo, toksvig + shading::FindVariant("tk19")->id);
  int widened = 0;
  for (auto d : {shading::DerivativeSource::kQuadFine, shading::DerivativeSource::kAnalytic})
    for (int y = 20; y < 48; y += 4)
      for (int x = 0; x < 48; x += 5) {
        const auto t = shading::ShadePixel(words, cam, s.light, s.material, toksvig, d, {}, {x, y});
        const auto c = shading::ShadePixel(words, cam, s.light, s.material, combo, d, {}, {x, y});
        if (!t.hit) continue;
        const auto& f = c.derivatives;
        const double spread = glm::dot(f.dn_dx, f.dn_dx) + glm::dot(f.dn_dy, f.dn_dy);
        const double want = std::clamp(t.alpha_eff.x * t.alpha_eff.x + std::min(2 * 0.25 * spread, 0.18), 0.0, 1.0);
        EXPECT_NEAR(c.alpha_eff.x * c.alpha_eff.x, want, 1e-9 * (1 + want)) << x << "," << y;
        EXPECT_NEAR(glm::length(c.normal - t.normal), 0, 1e-12);
        widened += c.alpha_eff.x > t.alpha_eff.x * (1 + 1e-6);
      }
  EXPECT_GT(widened, 10);
}

}  // namespace
}  // namespace shimmer::scene
