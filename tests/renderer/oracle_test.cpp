// The CPU double oracle on its own: BVH tracing against brute force, analytic
// ray-differential derivatives against quad differences, finite output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "generated_meshes.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"
#include "temp_dir.h"

namespace shimmer {
namespace {

double BruteForceDistance(const scene::Scene& s, glm::dvec3 o, glm::dvec3 d) {
  double best = 1e30;
  for (const auto& p : s.primitives) {
    if (p.type == scene::Primitive::Type::kSphere) {
      glm::dvec3 oc = o - p.a;
      double b = glm::dot(oc, d), c = glm::dot(oc, oc) - p.radius * p.radius, disc = b * b - c;
      if (disc >= 0) {
        double t = -b - std::sqrt(disc);
        if (t > 1e-4) best = std::min(best, t);
      }
    } else if (p.type == scene::Primitive::Type::kPlane && std::abs(d.y) > 1e-12) {
      double t = (p.radius - o.y) / d.y;
      if (t > 1e-4) best = std::min(best, t);
    }
  }
  return best;
}

TEST(Oracle, BvhTraceMatchesBruteForce) {
  scene::Scene s = scene::LoadScene("sphere-field").value();
  auto words = scene::PackScene(s);
  const int size = 48;
  shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kOrbit, s.rig, 3, 30, size, size);
  int hits = 0;
  for (int y = 0; y < size; y += 1)
    for (int x = 0; x < size; x += 1) {
      auto r =
          shading::ShadePixel(words, cam, s.light, s.material, 0, shading::DerivativeSource::kAnalytic, {}, {x, y});
      // The same ray in the test's own terms.
      double sx = cam.tan_half_fov_y * cam.width / cam.height, sy = cam.tan_half_fov_y;
      glm::dvec3 d = glm::normalize(cam.fwd + cam.right * ((2 * (x + 0.5) / size - 1) * sx) +
                                    cam.up * ((1 - 2 * (y + 0.5) / size) * sy));
      double t = BruteForceDistance(s, cam.pos, d);
      ASSERT_EQ(r.hit, t < 1e30) << x << "," << y;
      if (r.hit) {
        // Packed positions are float: agreement to float precision of the scene.
        EXPECT_NEAR(r.depth, t, 1e-5 * t) << x << "," << y;
        ++hits;
      }
    }
  EXPECT_GT(hits, size * size / 2);
}

// The reference kernel traces each sample against its pixel's candidate list
// instead of the BVH. The list must give exactly the BVH's nearest hit for
// every ray inside the pixel (corners included), in float as on the GPU, and
// it must be short for almost every pixel, else the kernel falls back. The
// mesh shots' lists hold triangles found by the pixel's pyramid: short on
// the low-poly meshes and the panel; the fine torus and the thin cable put
// 20-40 triangles (front and back) in each of their pixels, which walk the
// BVH per sample, so there only exactness is asked.
TEST(Oracle, PixelCandidatesGiveTheBvhHitForEveryRayInThePixel) {
  const glm::dvec2 offsets[] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.5}, {0.13, 0.91}, {0.77, 0.29}, {0.999, 0.001}};
  const std::string meshes = std::string(SHIMMER_SOURCE_DIR) + "/experiments/scenes/";
  struct Case {
    std::string scene;
    double max_overflow;  // share of pixels whose list is too long
  };
  const Case cases[] = {{"sphere", 0.02},
                        {"sphere-field", 0.02},
                        {"wires", 0.02},
                        {"bumpy-plane", 0.02},
                        {meshes + "tk19-fig1.json", 0.06},
                        {meshes + "torus-lowpoly.json", 0.02},
                        {meshes + "panel.json", 0.02},
                        {meshes + "torus-fine.json", 1.0},
                        {meshes + "cable.json", 1.0}};
  for (const Case& c : cases) {
    scene::Scene s = scene::LoadScene(c.scene).value();
    auto words = scene::PackScene(s);
    const int features = scene::SceneFeatures(s);
    // A kernel without meshes keeps fewer candidates than this oracle.
    const int limit = (features & shading::kSceneMeshes) ? shading::kMeshPixelCandidates : shading::kPixelCandidates;
    int pixels = 0, overflow = 0, rays = 0, hits = 0;
    for (int frame : {0, 7, 19}) {
      shading::CameraDesc cam =
          scene::CameraAt(frame == 7 ? scene::CameraPath::kDolly : scene::CameraPath::kOrbit, s.rig, frame, 30, 96, 72);
      for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
          ++pixels;
          for (glm::dvec2 o : offsets) {
            auto r = shading::TracePixelBothWays(words, features, cam, {x, y}, o);
            if (r.candidates > limit) {
              ++overflow;
              break;
            }
            ++rays;
            hits += r.scene_prim >= 0;
            ASSERT_EQ(r.candidate_prim, r.scene_prim) << c.scene << " frame " << frame << " pixel " << x << "," << y;
            ASSERT_EQ(r.candidate_t, r.scene_t) << c.scene << " frame " << frame << " pixel " << x << "," << y;
          }
        }
    }
    EXPECT_GT(hits, c.max_overflow < 1 ? rays / 20 : 0) << c.scene;
    EXPECT_LE(overflow, c.max_overflow * pixels) << c.scene << ": " << overflow << " of " << pixels << " pixels overflow";
  }
}

// Hard shadows against a known answer: a ball over a plane under a
// directional light. A plane point whose ray to the light passes through
// the ball (clear of its rim by a margin) gets no light; one whose ray
// passes clear of it gets the unshadowed light. Without "shadows" nothing is dark.
TEST(Oracle, ShadowsFallWhereTheRayToTheLightMeetsAnOccluder) {
  const glm::dvec3 centre{0, 0.6, 0}, to_light = glm::normalize(glm::dvec3{0.3, 1, 0.2});
  const double radius = 0.4;
  for (bool shadows : {true, false}) {
    const std::string json = std::string(R"({"primitives": [{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.4},
        {"type": "plane", "height": 0}], "light": {"direction": [0.3, 1, 0.2], "shadows": )") +
                             (shadows ? "true" : "false") +
                             R"(}, "material": "ggx:0.3", "camera": {"target": [0, 0.2, 0], "distance": 4,
        "elevation_deg": 40, "fov_y_deg": 40}})";
    scene::Scene s = scene::ParseSceneJson(json, "shadow.json").value();
    auto words = scene::PackScene(s);
    const int size = 64;
    shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kStatic, s.rig, 0, 30, size, size);
    int dark = 0, lit = 0;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        auto r =
            shading::ShadePixel(words, cam, s.light, s.material, 0, shading::DerivativeSource::kAnalytic, {}, {x, y});
        double sx = cam.tan_half_fov_y * cam.width / cam.height, sy = cam.tan_half_fov_y;
        glm::dvec3 d = glm::normalize(cam.fwd + cam.right * ((2 * (x + 0.5) / size - 1) * sx) +
                                      cam.up * ((1 - 2 * (y + 0.5) / size) * sy));
        const glm::dvec3 q = cam.pos + d * r.depth;
        if (!r.hit || std::abs(q.y) > 1e-4) continue;  // the ball, or the sky
        // Closest approach of the ray q + t l (t > 0) to the ball's centre.
        const double t = glm::dot(centre - q, to_light);
        const double miss = t > 0 ? glm::length(q + to_light * t - centre) : 1e30;
        const double luminance = r.diffuse.x + r.diffuse.y + r.diffuse.z;
        if (miss < radius - 1e-3) {
          ++dark;
          if (shadows) {
            EXPECT_EQ(luminance, 0) << x << "," << y;
            EXPECT_EQ(r.specular.x + r.specular.y + r.specular.z, 0) << x << "," << y;
          } else {
            EXPECT_GT(luminance, 0) << x << "," << y;
          }
        } else if (miss > radius + 1e-3) {
          ++lit;
          EXPECT_GT(luminance, 0) << x << "," << y;
        }
      }
    EXPECT_GT(dark, 50);
    EXPECT_GT(lit, 500);
  }
}

// A mesh's roughness texture scales the alpha in use per texel by
// (G / mean G)^2 (scene.glsl, "Roughness textures"): on a quad whose texture
// has G = 64 on its left half and 192 on its right, a pixel whose point lies
// well inside a half (its bilinear read all one value) shades exactly as the
// untextured quad does with alpha x 0.25 or x 2.25, with every filter and
// derivative source; the texture's mean is the material's alpha.
TEST(Oracle, ARoughnessTextureScalesAlphaByItsTexel) {
  shimmer::testing::TempDir textured_dir, plain_dir;
  scene::Scene textured = scene::LoadScene(shimmer::testing::WriteRoughnessQuad(textured_dir.path()).string()).value();
  scene::Scene plain = scene::LoadScene(shimmer::testing::WriteRoughnessQuad(plain_dir.path(), false).string()).value();
  ASSERT_TRUE(textured.primitives.at(0).roughness_map);
  ASSERT_FALSE(plain.primitives.at(0).roughness_map);
  EXPECT_NE(scene::SceneFeatures(textured) & shading::kSceneRoughnessMaps, 0);
  EXPECT_EQ(scene::SceneFeatures(plain) & shading::kSceneRoughnessMaps, 0);
  // The asset's own material: alpha = (Pr x mean G)^2, mean G = 128 / 255.
  EXPECT_NEAR(textured.material.alpha.x, std::pow(0.5 * 128 / 255, 2), 1e-12);
  const auto textured_words = scene::PackScene(textured), plain_words = scene::PackScene(plain);
  const int size = 48;
  shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kStatic, textured.rig, 0, 30, size, size);
  shading::MaterialDesc base;
  base.alpha = {0.2, 0.2};
  int left = 0, right = 0;
  for (const char* variant : {"none", "tk19", "k16-ggx-rect-stable"})
    for (auto d : {shading::DerivativeSource::kQuadFine, shading::DerivativeSource::kAnalytic})
      for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
          const shading::VariantInfo* info = shading::FindVariant(variant);
          ASSERT_NE(info, nullptr);
          const int id = info->id;
          const auto params = shading::ResolveParams(*info, {}).value();
          auto r = shading::ShadePixel(textured_words, cam, textured.light, base, id, d, params, {x, y});
          if (!r.hit) continue;
          double sx = cam.tan_half_fov_y * cam.width / cam.height, sy = cam.tan_half_fov_y;
          glm::dvec3 dir = glm::normalize(cam.fwd + cam.right * ((2 * (x + 0.5) / size - 1) * sx) +
                                          cam.up * ((1 - 2 * (y + 0.5) / size) * sy));
          const double u = (cam.pos.x + dir.x * r.depth + 1) / 2;
          double factor = 0;
          if (u > 0.1 && u < 0.4) factor = 0.25, ++left;
          if (u > 0.6 && u < 0.9) factor = 2.25, ++right;
          if (factor == 0) continue;
          shading::MaterialDesc scaled = base;
          scaled.alpha = base.alpha * factor;
          auto expected = shading::ShadePixel(plain_words, cam, plain.light, scaled, id, d, params, {x, y});
          ASSERT_TRUE(expected.hit);
          const glm::dvec3 a = r.specular, b = expected.specular;
          EXPECT_NEAR(a.x, b.x, 1e-9 * (1 + std::abs(b.x))) << variant << " " << x << "," << y << " u " << u;
          EXPECT_NEAR(a.y + a.z, b.y + b.z, 1e-9 * (1 + std::abs(b.y + b.z))) << variant << " " << x << "," << y;
        }
  EXPECT_GT(left, 200);
  EXPECT_GT(right, 200);
}

// On a large smooth sphere the ray-differential derivatives equal the quad
// differences to first order (the difference is a half-pixel offset times curvature).
TEST(Oracle, AnalyticDerivativesAgreeWithQuadDifferencesOnSmoothSurface) {
  scene::Scene s = scene::LoadScene("sphere").value();
  auto words = scene::PackScene(s);
  const int size = 512;
  shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kStatic, s.rig, 0, 30, size, size);
  int checked = 0;
  for (glm::ivec2 px : {glm::ivec2(256, 256), glm::ivec2(230, 280), glm::ivec2(300, 220), glm::ivec2(200, 200)}) {
    auto a = shading::ShadePixel(words, cam, s.light, s.material, 0, shading::DerivativeSource::kAnalytic, {}, px);
    auto q = shading::ShadePixel(words, cam, s.light, s.material, 0, shading::DerivativeSource::kQuadFine, {}, px);
    ASSERT_TRUE(a.hit);
    const auto& fa = a.derivatives;
    const auto& fq = q.derivatives;
    double scale = glm::length(fa.dhpp_dx) + glm::length(fa.dhpp_dy);
    ASSERT_GT(scale, 1e-5);
    EXPECT_LT(glm::length(fa.dhpp_dx - fq.dhpp_dx), 0.03 * scale) << px.x << "," << px.y;
    EXPECT_LT(glm::length(fa.dhpp_dy - fq.dhpp_dy), 0.03 * scale) << px.x << "," << px.y;
    double nscale = glm::length(fa.dn_dx) + glm::length(fa.dn_dy);
    EXPECT_LT(glm::length(fa.dn_dx - fq.dn_dx), 0.03 * nscale);
    EXPECT_LT(glm::length(fa.dng_dy - fq.dng_dy), 0.03 * nscale);
    // A unit sphere seen from distance 4: |dn| is the pixel footprint on the surface, about
    // 2 * 4 * tan(17.5 deg) / 512 / cos(theta) (wider at grazing angles).
    double pixel = 2 * 3 * std::tan(17.5 * 3.14159265358979 / 180) / size;
    EXPECT_GT(glm::length(fa.dn_dx), 0.8 * pixel);
    ++checked;
  }
  EXPECT_EQ(checked, 4);
}

// Why seed 000's parallelogram does not blow up in shimmer's scenes where
// Tokuyoshi and Kaplanyan 2019 (Fig. 1) report RMSE 13124 for it: per scene,
// on the quad footprints of frame 0 (orbit, 128^2, GGX alpha = 0.01), the
// largest slope |hpp| and slope derivative |d hpp| any pixel sees, and the
// textbook evaluation in float (det R = r00 r11 - r01^2 and R^-1) beside
// shimmer's (det and the quadratic form as sums of squares) against double.
// On `bumpy-plane`, the grazing scene, h.z stays above 0.3 (|hpp| < 3): the
// half vector never comes near the horizon where the slope's finite
// differences explode (the reports, "Beyond the papers").
TEST(Oracle, ParallelogramFootprintsOfTheScenesAndTheTextbookForm) {
  const shading::VariantInfo* v = shading::FindVariant("k16-beckmann-parallelogram");
  const float a = 0.01f;
  for (const char* name : {"bumpy-plane", "sphere-field", "wires"}) {
    scene::Scene s = scene::LoadScene(name).value();
    auto words = scene::PackScene(s);
    const int size = 128;
    shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kOrbit, s.rig, 0, 30, size, size);
    int pixels = 0, textbook_failures = 0, shipped_failures = 0;
    double max_slope = 0, max_derivative = 0;
    for (double sigma2 : {0.25, 1.0}) {
      shading::Params<double> pd;
      pd.sigma2 = sigma2;
      shading::Params<float> pf;
      pf.sigma2 = float(sigma2);
      for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
          const auto o = shading::ShadePixel(words, cam, s.light, s.material, 0,
                                             shading::DerivativeSource::kQuadFine, {}, {x, y});
          if (!o.hit) continue;
          ++pixels;
          const shading::Footprint<double>& fd = o.derivatives;
          max_slope = std::max(max_slope, glm::length(fd.hpp));
          max_derivative = std::max({max_derivative, glm::length(fd.dhpp_dx), glm::length(fd.dhpp_dy)});
          shading::Footprint<float> ff;
          ff.hpp = glm::vec2(fd.hpp);
          ff.dhpp_dx = glm::vec2(glm::clamp(fd.dhpp_dx, glm::dvec2(-1e4), glm::dvec2(1e4)));
          ff.dhpp_dy = glm::vec2(glm::clamp(fd.dhpp_dy, glm::dvec2(-1e4), glm::dvec2(1e4)));
          const double want = shading::EvaluateVariant<double>(v->id, shading::Ndf::kGgx, {a, a}, fd, pd).density;
          const float got = shading::EvaluateVariant<float>(v->id, shading::Ndf::kGgx, {a, a}, ff, pf).density;
          // The textbook: R = diag(a^2) + 2 U U^T, U = sqrt(sigma2) d hpp, in float.
          const float u = std::sqrt(float(sigma2));
          const glm::vec2 ux = u * ff.dhpp_dx, uy = u * ff.dhpp_dy, sl = ff.hpp;
          const float r00 = a * a + 2 * (ux.x * ux.x + uy.x * uy.x);
          const float r11 = a * a + 2 * (ux.y * ux.y + uy.y * uy.y);
          const float r01 = 2 * (ux.x * ux.y + uy.x * uy.y);
          const float det = r00 * r11 - r01 * r01;
          const float q = (r11 * sl.x * sl.x + r00 * sl.y * sl.y - 2 * r01 * sl.x * sl.y) / det;
          const float q2 = 1 + glm::dot(sl, sl);
          const float textbook = q2 * q2 / (3.14159265f * std::sqrt(det) * (1 + q) * (1 + q));
          auto off = [&](double value) {
            return !std::isfinite(value) || value < 0 || std::abs(value - want) > 1e-2 * want + 1e-6;
          };
          textbook_failures += off(textbook);
          shipped_failures += off(got);
        }
    }
    std::printf("%-12s quad, GGX 0.01: max |hpp| %.3g, max |d hpp| %.3g per pixel; off from double: textbook %d, "
                "shimmer %d of %d evaluations\n",
                name, max_slope, max_derivative, textbook_failures, shipped_failures, pixels);
    EXPECT_EQ(shipped_failures, 0) << name;
    if (std::string(name) == "bumpy-plane") {
      EXPECT_LT(max_slope, 3.0);
    }
  }
}

TEST(Oracle, EveryVariantGivesFiniteOutputAtSilhouettesAndGrazing) {
  for (const char* name : {"sphere", "wires", "bumpy-plane"}) {
    scene::Scene s = scene::LoadScene(name).value();
    auto words = scene::PackScene(s);
    shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kOrbit, s.rig, 5, 30, 24, 24);
    for (const auto& v : shading::Variants())
      for (auto d : {shading::DerivativeSource::kAnalytic, shading::DerivativeSource::kQuadFine,
                     shading::DerivativeSource::kQuadCoarse}) {
        auto p = shading::ResolveParams(v, {}).value();
        for (int y = 0; y < 24; ++y)
          for (int x = 0; x < 24; ++x) {
            auto r = shading::ShadePixel(words, cam, s.light, s.material, v.id, d, p, {x, y});
            ASSERT_TRUE(std::isfinite(r.specular.x) && std::isfinite(r.diffuse.x) && std::isfinite(r.alpha_eff.x) &&
                        std::isfinite(r.footprint.x))
                << name << " " << v.name << " " << x << "," << y;
          }
      }
  }
}

}  // namespace
}  // namespace shimmer
