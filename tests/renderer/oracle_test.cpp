// The CPU double oracle on its own: BVH tracing against brute force, analytic
// ray-differential derivatives against quad differences, finite output.
#include <gtest/gtest.h>

#include <cmath>

#include "shimmer/renderer/scene.h"
#include "shimmer/renderer/shading.h"

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
// it must be short for almost every pixel, else the kernel falls back.
TEST(Oracle, PixelCandidatesGiveTheBvhHitForEveryRayInThePixel) {
  const glm::dvec2 offsets[] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.5}, {0.13, 0.91}, {0.77, 0.29}, {0.999, 0.001}};
  for (const char* name : {"sphere", "sphere-field", "wires", "bumpy-plane"}) {
    scene::Scene s = scene::LoadScene(name).value();
    auto words = scene::PackScene(s);
    const int features = scene::SceneFeatures(s);
    int pixels = 0, overflow = 0, rays = 0, hits = 0;
    for (int frame : {0, 7, 19}) {
      shading::CameraDesc cam =
          scene::CameraAt(frame == 7 ? scene::CameraPath::kDolly : scene::CameraPath::kOrbit, s.rig, frame, 30, 96, 72);
      for (int y = 0; y < cam.height; ++y)
        for (int x = 0; x < cam.width; ++x) {
          ++pixels;
          for (glm::dvec2 o : offsets) {
            auto r = shading::TracePixelBothWays(words, features, cam, {x, y}, o);
            if (r.candidates > shading::kPixelCandidates) {
              ++overflow;
              break;
            }
            ++rays;
            hits += r.scene_prim >= 0;
            ASSERT_EQ(r.candidate_prim, r.scene_prim) << name << " frame " << frame << " pixel " << x << "," << y;
            ASSERT_EQ(r.candidate_t, r.scene_t) << name << " frame " << frame << " pixel " << x << "," << y;
          }
        }
    }
    EXPECT_GT(hits, rays / 20) << name;
    EXPECT_LT(overflow, pixels / 50) << name << ": " << overflow << " of " << pixels << " pixels overflow";
  }
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
