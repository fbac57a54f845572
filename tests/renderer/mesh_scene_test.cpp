// Mesh assets in scenes: placement and packing, the asset's content in the
// job fingerprint, one error per bad asset, and the CPU double oracle on mesh
// pixels: scene.glsl's BVH walk against the CPU BVH, interpolated normals,
// and analytic derivatives (ray differentials through the interpolated
// normal) against the quad's finite differences of the renderer's own normals.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "cli_run.h"
#include "generated_meshes.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"
#include "temp_dir.h"

namespace shimmer {
namespace {

using testing::TempDir;
namespace fs = std::filesystem;

scene::Scene LoadOk(const fs::path& file) {
  auto s = scene::LoadScene(file.string());
  EXPECT_TRUE(s) << s.error();
  return s ? *s : scene::Scene{};
}

TEST(SceneAssets, PlacesAnAssetBesideAnalyticPrimitives) {
  TempDir dir;
  testing::WriteSphereObj(dir.path() / "ball.obj", 2, {0, 0, 0}, 1);
  const scene::Scene s =
      LoadOk(testing::WriteMeshScene(dir.path(), "ball.obj", R"({"translate": [0.5, 0, 0], "scale": 0.8})"));
  ASSERT_EQ(s.primitives.size(), 2u);
  const scene::Primitive& p = s.primitives[1];
  ASSERT_EQ(p.type, scene::Primitive::Type::kMesh);
  ASSERT_NE(p.mesh, nullptr);
  EXPECT_EQ(p.mesh->mesh.triangle_count(), 320u);
  // The icosphere's vertices lie on the unit sphere; placed, on the sphere of
  // radius 0.8 about (0.5, 0, 0), and the bounds hold them.
  for (const glm::vec3& v : p.mesh->mesh.positions)
    ASSERT_NEAR(glm::length(glm::dvec3(v) - glm::dvec3(0.5, 0, 0)), 0.8, 1e-5);
  EXPECT_GT(p.a.x, 0.5 - 0.8 - 1e-5);
  EXPECT_LT(p.a.x, 0.5 - 0.8 * 0.8);
  EXPECT_LT(p.b.x, 0.5 + 0.8 + 1e-5);
  EXPECT_EQ(scene::SceneFeatures(s), shading::kScenePlanes | shading::kSceneMeshes);
  EXPECT_EQ(s.material.alpha.x, 0.08);
  // Header, one BVH node (one bounded primitive), two primitives, the mesh.
  EXPECT_EQ(scene::PackScene(s).size(), 1 + 2 + 3 * 2 + scene::PackedMeshWords(*p.mesh));
}

TEST(SceneAssets, EditingTheAssetMovesTheFingerprintNotTheKernel) {
  TempDir dir;
  const fs::path obj = dir.path() / "ball.obj";
  testing::WriteSphereObj(obj, 1, {0, 0, 0}, 1);
  const fs::path file = testing::WriteMeshScene(dir.path(), "ball.obj");
  auto fingerprint = [&] {
    render::RenderSettings r;
    r.scene = LoadOk(file);
    r.material = r.scene.material;
    r.variant = "none";
    r.width = r.height = 16;
    r.frames = 1;
    auto f = render::FingerprintRender(r);
    EXPECT_TRUE(f) << f.error();
    return f ? *f : render::RenderFingerprint{};
  };
  const render::RenderFingerprint a = fingerprint();
  EXPECT_EQ(fingerprint().inputs, a.inputs);
  testing::WriteSphereObj(obj, 1, {0, 0, 0}, 0.9);
  const render::RenderFingerprint b = fingerprint();
  EXPECT_EQ(b.kernel, a.kernel);
  EXPECT_NE(b.inputs, a.inputs);
}

void ExpectSceneError(const fs::path& file, const std::string& where, const std::string& problem) {
  auto s = scene::LoadScene(file.string());
  ASSERT_FALSE(s) << file;
  EXPECT_NE(s.error().find(file.string() + ": " + where), std::string::npos) << s.error();
  EXPECT_NE(s.error().find(problem), std::string::npos) << s.error();
  EXPECT_EQ(s.error().find('\n'), std::string::npos) << s.error();
}

// Placements are kept per process, and a placed mesh keeps its texture
// files' paths: an equal copy of an asset in another folder reads its own
// texture, also after the first copy is gone (two tests that each wrote the
// same quad once shared the first one's deleted texture path).
TEST(SceneAssets, AnEqualCopyElsewhereReadsItsOwnTextures) {
  std::filesystem::path second_scene;
  shimmer::testing::TempDir second;
  {
    shimmer::testing::TempDir first;
    auto a = scene::LoadScene(shimmer::testing::WriteRoughnessQuad(first.path()).string());
    ASSERT_TRUE(a) << a.error();
    ASSERT_TRUE(a->primitives.at(0).roughness_map);
    second_scene = shimmer::testing::WriteRoughnessQuad(second.path());
  }  // the first copy, texture included, is deleted here
  auto b = scene::LoadScene(second_scene.string());
  ASSERT_TRUE(b) << b.error();
  ASSERT_TRUE(b->primitives.at(0).roughness_map);
}

TEST(SceneAssets, BadAssetsAreOneErrorNamingTheFileAndTheProblem) {
  TempDir dir;
  ExpectSceneError(testing::WriteMeshScene(dir.path(), "nope.obj"), "/assets/0/file: ",
                   (dir.path() / "nope.obj").string() + ": no such file");
  std::ofstream(dir.path() / "bad.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n";
  ExpectSceneError(testing::WriteMeshScene(dir.path(), "bad.obj"), "/assets/0/file: ",
                   (dir.path() / "bad.obj").string());
  std::ofstream(dir.path() / "flat.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
  ExpectSceneError(testing::WriteMeshScene(dir.path(), "flat.obj"), "/assets/0/file: ", "zero area");
  testing::WriteSphereObj(dir.path() / "ball.obj", 0, {0, 0, 0}, 1);
  ExpectSceneError(testing::WriteMeshScene(dir.path(), "ball.obj", R"({"scale": 0})"), "/assets/0/transform/scale: ",
                   "nonzero");
  ExpectSceneError(testing::WriteMeshScene(dir.path(), "ball.obj", R"({"matrix": [1, 2]})"),
                   "/assets/0/transform/matrix: ", "16 finite numbers");
  ExpectSceneError(testing::WriteMeshScene(dir.path(), "ball.obj", R"({"spin": 1})"), "/assets/0/transform/spin: ",
                   "unknown key");
  const fs::path two = dir.path() / "two-materials.json";
  std::ofstream(two) << R"({"material": "ggx:0.1", "assets": [{"file": "ball.obj", "material": "ggx:0.2"}]})";
  ExpectSceneError(two, "/assets/0/material: ", "give it once");
  const fs::path none = dir.path() / "no-assets.json";
  std::ofstream(none) << R"({"assets": []})";
  ExpectSceneError(none, "/assets: ", "non-empty array");
}

TEST(SceneAssets, CliRefusesAMissingAssetWithExitTwo) {
  TempDir dir;
  const fs::path scene = testing::WriteMeshScene(dir.path(), "nope.obj");
  const testing::CliRun v = testing::RunShimmer(SHIMMER_CLI, "scene validate " + scene.string());
  EXPECT_EQ(v.exit_code, 2) << v.output;
  EXPECT_NE(v.output.find("nope.obj: no such file"), std::string::npos) << v.output;
  const testing::CliRun r = testing::RunShimmer(
      SHIMMER_CLI, "render --asset " + (dir.path() / "nope.obj").string() + " --out " + (dir.path() / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("nope.obj: no such file"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
  testing::WriteSphereObj(dir.path() / "ball.obj", 0, {0, 0, 0}, 1);
  const testing::CliRun both = testing::RunShimmer(
      SHIMMER_CLI, "render --asset " + (dir.path() / "ball.obj").string() + " --scene sphere --out " +
                       (dir.path() / "out").string());
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_NE(both.output.find("--asset and --scene"), std::string::npos) << both.output;
}

TEST(SceneAssets, CliValidatesAMeshScene) {
  TempDir dir;
  testing::WriteSphereObj(dir.path() / "ball.obj", 2, {0, 0, 0}, 1);
  const fs::path scene = testing::WriteMeshScene(dir.path(), "ball.obj");
  const testing::CliRun v = testing::RunShimmer(SHIMMER_CLI, "scene validate " + scene.string());
  EXPECT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("2 primitives (0 spheres, 0 capsules, 1 planes, 1 meshes of 320 triangles)"),
            std::string::npos)
      << v.output;
}

TEST(SceneAssets, FramingRigSeesTheWholeAsset) {
  TempDir dir;
  testing::WriteSphereObj(dir.path() / "ball.obj", 1, {3, 1, -2}, 0.5);
  auto s = scene::AssetScene(dir.path() / "ball.obj");
  ASSERT_TRUE(s) << s.error();
  const glm::dvec3 centre = (s->primitives[0].a + s->primitives[0].b) * 0.5;
  EXPECT_LT(glm::length(s->rig.target - glm::dvec3(3, 1, -2)), 0.05);
  for (int frame : {0, 10, 30})
    for (scene::CameraPath path : {scene::CameraPath::kOrbit, scene::CameraPath::kStatic}) {
      const shading::CameraDesc c = scene::CameraAt(path, s->rig, frame, 30, 64, 64);
      // The bounding sphere lies inside the view cone, however the path moves.
      const glm::dvec3 v = centre - c.pos;
      const double angle = std::acos(std::min(1.0, glm::dot(glm::normalize(v), c.fwd)));
      const double radius = 0.5;
      EXPECT_LT(angle + std::asin(std::min(1.0, radius / glm::length(v))), std::atan(c.tan_half_fov_y) + 1e-9)
          << "frame " << frame;
    }
}

// The oracle's nearest hit on the mesh is the CPU BVH's (triangle_bvh.cpp):
// the same triangles at the same distance, to float precision.
TEST(MeshOracle, TraceMatchesTheCpuBvh) {
  TempDir dir;
  testing::WriteSphereObj(dir.path() / "ball.obj", 3, {0.2, 0, 0}, 1);
  auto s = scene::AssetScene(dir.path() / "ball.obj");
  ASSERT_TRUE(s) << s.error();
  const scene::PlacedMesh& mesh = *s->primitives[0].mesh;
  const auto words = scene::PackScene(*s);
  const int size = 48;
  const shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kOrbit, s->rig, 3, 30, size, size);
  int hits = 0, differ = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const auto o =
          shading::ShadePixel(words, cam, s->light, s->material, 0, shading::DerivativeSource::kAnalytic, {}, {x, y});
      const double sx = cam.tan_half_fov_y * cam.width / cam.height, sy = cam.tan_half_fov_y;
      const glm::dvec3 d = glm::normalize(cam.fwd + cam.right * ((2 * (x + 0.5) / size - 1) * sx) +
                                          cam.up * ((1 - 2 * (y + 0.5) / size) * sy));
      const auto cpu = mesh.bvh.Intersect(glm::vec3(cam.pos), glm::vec3(d), 1e30f);
      if (o.hit != cpu.has_value()) {
        ++differ;  // a ray through the silhouette, decided by rounding
        continue;
      }
      if (!o.hit) continue;
      ++hits;
      EXPECT_NEAR(o.depth, cpu->t, 1e-5 * cpu->t) << x << "," << y;
      // Interpolated, not faceted: on a triangle whose corners lie on the
      // sphere with the sphere's normals, normalize(sum b_i n_i) is the
      // direction from the centre to the hit point exactly.
      const glm::dvec3 p = cam.pos + d * o.depth;
      EXPECT_LT(glm::length(o.normal - glm::normalize(p - glm::dvec3(0.2, 0, 0))), 1e-4) << x << "," << y;
    }
  EXPECT_GT(hits, size * size / 3);  // the rig frames the ball
  EXPECT_LE(differ, size / 4);
}

// Ray differentials through the interpolated normal (dN/dx of
// normalize(sum b_i n_i)) against the quad's differences of the renderer's
// own normals, the helper pixels continued on the centre's triangle as a
// rasterizer's helper lanes are: equal to first order in the pixel.
TEST(MeshOracle, AnalyticDerivativesAgreeWithQuadDifferences) {
  TempDir dir;
  testing::WriteSphereObj(dir.path() / "ball.obj", 3, {0, 0, 0}, 1);
  auto s = scene::AssetScene(dir.path() / "ball.obj");
  ASSERT_TRUE(s) << s.error();
  const auto words = scene::PackScene(*s);
  const int size = 512;
  const shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kStatic, s->rig, 0, 30, size, size);
  int checked = 0;
  for (glm::ivec2 px : {glm::ivec2(256, 256), glm::ivec2(230, 280), glm::ivec2(300, 220), glm::ivec2(200, 200),
                        glm::ivec2(180, 330)}) {
    auto a = shading::ShadePixel(words, cam, s->light, s->material, 0, shading::DerivativeSource::kAnalytic, {}, px);
    auto q = shading::ShadePixel(words, cam, s->light, s->material, 0, shading::DerivativeSource::kQuadFine, {}, px);
    ASSERT_TRUE(a.hit);
    const auto& fa = a.derivatives;
    const auto& fq = q.derivatives;
    const double nscale = glm::length(fa.dn_dx) + glm::length(fa.dn_dy);
    ASSERT_GT(nscale, 1e-5);
    EXPECT_LT(glm::length(fa.dn_dx - fq.dn_dx), 0.02 * nscale) << px.x << "," << px.y;
    EXPECT_LT(glm::length(fa.dn_dy - fq.dn_dy), 0.02 * nscale) << px.x << "," << px.y;
    const double hscale = glm::length(fa.dhpp_dx) + glm::length(fa.dhpp_dy);
    EXPECT_LT(glm::length(fa.dhpp_dx - fq.dhpp_dx), 0.03 * hscale) << px.x << "," << px.y;
    EXPECT_LT(glm::length(fa.dhpp_dy - fq.dhpp_dy), 0.03 * hscale) << px.x << "," << px.y;
    // A flat triangle's geometric normal does not turn.
    EXPECT_EQ(glm::length(fa.dng_dx), 0.0);
    ++checked;
  }
  EXPECT_EQ(checked, 5);
}

// `shimmer render --asset` end to end (Vulkan): frames and sequence.json of
// the asset alone; a bad --material is a usage error before anything renders.
TEST(GpuRenderAsset, CliRendersAFramedAsset) {
  TempDir dir;
  testing::WriteSphereObj(dir.path() / "ball.obj", 2, {0, 0, 0}, 1);
  const std::string args = "render --asset " + (dir.path() / "ball.obj").string() +
                           " --variant tk19 --frames 2 --size 24 24 --out " + (dir.path() / "out").string();
  const testing::CliRun r = testing::RunShimmer(SHIMMER_CLI, args);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 frames of ball.obj (orbit, tk19)"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(dir.path() / "out" / "sequence.json"));
  EXPECT_TRUE(fs::exists(dir.path() / "out" / "frame_0001.exr"));
  const testing::CliRun bad = testing::RunShimmer(SHIMMER_CLI, args + "-bad --material ggx:-1");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out-bad"));
}

}  // namespace
}  // namespace shimmer
