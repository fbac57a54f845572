// Normal maps in the shading core (normal_map.glsl, scene.glsl), in double on
// the CPU: uv and tangent frames of each primitive, the mip-chain sampler,
// and the normal-map filters' known answers.
#include <gtest/gtest.h>

#include <cmath>

#include "shimmer/renderer/normal_map.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/renderer/shading.h"

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

}  // namespace
}  // namespace shimmer::scene
