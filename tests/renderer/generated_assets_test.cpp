// The mesh shots' content (experiments/scenes) is what scripts/generate-assets.py
// writes, byte for byte, and loads as the shots need it: the low-poly torus's
// vertex normals are the true torus's (so its interpolated normals turn across
// flat triangles), the fine one has the same shape, the TK19 Fig. 1 props rest
// on the ground through the node hierarchy, the panel's glTF material keeps
// its textures, and each scene names its geometry class.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "shimmer/renderer/mesh_loading.h"
#include "shimmer/renderer/scene.h"
#include "temp_dir.h"

namespace shimmer::scene {
namespace {

namespace fs = std::filesystem;

const fs::path kScenes = fs::path(SHIMMER_SOURCE_DIR) / "experiments" / "scenes";

std::string Bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::set<std::string> Names(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

TEST(GeneratedAssets, CommittedFilesAreTheScriptsOutput) {
  testing::TempDir dir;
  const std::string command = "python3 '" + (fs::path(SHIMMER_SOURCE_DIR) / "scripts" / "generate-assets.py").string() +
                              "' '" + dir.path().string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  EXPECT_EQ(Names(dir.path()), Names(kScenes)) << "experiments/scenes holds a file the script does not write, or lacks one";
  for (const std::string& name : Names(dir.path()))
    EXPECT_TRUE(Bytes(dir.path() / name) == Bytes(kScenes / name))
        << name << " differs from the script's output: run python3 scripts/generate-assets.py";
}

double TorusDistance(glm::vec3 p, double major, double minor) {
  const double ring = std::hypot(double(p.x), double(p.z)) - major;
  return std::hypot(ring, double(p.y)) - minor;
}

TEST(GeneratedAssets, TheToriShareTheShapeAndTheTrueNormals) {
  for (const char* file : {"torus-lowpoly.gltf", "torus-fine.glb"}) {
    SCOPED_TRACE(file);
    auto asset = LoadMeshAsset(kScenes / file);
    ASSERT_TRUE(asset) << asset.error();
    ASSERT_EQ(asset->meshes.size(), 1u);
    const TriangleMesh& m = asset->meshes[0];
    EXPECT_EQ(m.triangle_count(), std::string(file) == "torus-fine.glb" ? 2u * 192 * 96 : 2u * 12 * 6);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
      const glm::vec3 p = m.positions[i];
      ASSERT_NEAR(TorusDistance(p, 1.0, 0.4), 0.0, 1e-5) << "vertex " << i;
      // The exact normal: from the tube's centre line to the vertex.
      const glm::vec3 centre = glm::normalize(glm::vec3(p.x, 0, p.z));
      const glm::vec3 exact = glm::normalize(p - centre);
      ASSERT_GT(glm::dot(m.normals[i], exact), 1 - 1e-5) << "vertex " << i;
    }
  }
}

TEST(GeneratedAssets, EachSceneLoadsWithItsGeometryClass) {
  const std::pair<const char*, const char*> expected[] = {{"torus-lowpoly.json", "low-poly mesh"},
                                                          {"torus-fine.json", "fine mesh"},
                                                          {"cable.json", "thin mesh"},
                                                          {"panel.json", "normal-mapped mesh"},
                                                          {"tk19-fig1.json", "grazing plane and low-poly meshes"}};
  for (const auto& [file, geometry_class] : expected) {
    auto scene = LoadScene((kScenes / file).string());
    ASSERT_TRUE(scene) << scene.error();
    EXPECT_EQ(scene->geometry_class, geometry_class) << file;
    EXPECT_TRUE(SceneFeatures(*scene) & shading::kSceneMeshes) << file;
  }
}

TEST(GeneratedAssets, Tk19PropsRestOnTheGroundThroughTheHierarchy) {
  auto asset = LoadMeshAsset(kScenes / "tk19-fig1.gltf");
  ASSERT_TRUE(asset) << asset.error();
  ASSERT_EQ(asset->meshes.size(), 6u);  // the ground, four spheres and the ring
  for (const TriangleMesh& m : asset->meshes) {
    float lowest = 1e9f;
    for (const glm::vec3& p : m.positions) lowest = std::min(lowest, p.y);
    // The spheres' icosahedron has a vertex at its bottom only after a turn;
    // the lowest vertex lies within the facets' sagitta of the ground.
    EXPECT_GE(lowest, -1e-5f) << m.name;
    EXPECT_LE(lowest, 0.1f) << m.name;
  }
  // The parent node moves the props by -0.5 along z: the first sphere's centre.
  glm::dvec3 sum(0);
  for (const glm::vec3& p : asset->meshes[1].positions) sum += glm::dvec3(p);
  const glm::dvec3 centre = sum / double(asset->meshes[1].positions.size());
  EXPECT_NEAR(centre.x, -1.6, 1e-4);
  EXPECT_NEAR(centre.z, 0.4 - 0.5, 1e-4);
}

TEST(GeneratedAssets, ThePanelKeepsItsGltfMaterial) {
  auto asset = LoadMeshAsset(kScenes / "panel.gltf");
  ASSERT_TRUE(asset) << asset.error();
  const MeshMaterial& m = asset->meshes.at(0).material;
  EXPECT_EQ(m.normal_texture.file.filename(), "panel-normal.png");
  EXPECT_DOUBLE_EQ(m.normal_scale, 0.8);
  EXPECT_EQ(m.metallic_roughness_texture.file.filename(), "panel-roughness.png");
  EXPECT_DOUBLE_EQ(m.metallic, 1.0);
}

// glTF's metallic-roughness material as the scene's where the scene gives
// none: alpha = (roughnessFactor x the texture's mean G)^2, f0 the base colour
// of a metal, no diffuse; the normal texture as the mesh's normal map.
TEST(GeneratedAssets, ASceneWithoutMaterialShadesWithTheAssetsOwn) {
  // panel-roughness.png: G = round(255 (0.1 + 0.25 w)), w = 0.5 + 0.5 sin(2 pi 2 (x + 0.5) / 256) per column.
  double g = 0;
  for (int x = 0; x < 256; ++x)
    g += std::round(255 * (0.1 + 0.25 * (0.5 + 0.5 * std::sin(2 * 3.14159265358979323846 * 2 * (x + 0.5) / 256)))) / 255;
  const double alpha = (g / 256) * (g / 256);
  auto scene = LoadScene((kScenes / "panel.json").string());
  ASSERT_TRUE(scene) << scene.error();
  EXPECT_NEAR(scene->material.alpha.x, alpha, 1e-9);
  EXPECT_NEAR(scene->material.f0.x, 0.9, 1e-9);
  EXPECT_NEAR(scene->material.f0.z, 0.92, 1e-9);
  EXPECT_EQ(scene->material.albedo, glm::dvec3(0));
  ASSERT_EQ(scene->primitives.size(), 1u);
  ASSERT_NE(scene->primitives[0].normal_map, nullptr);
  EXPECT_DOUBLE_EQ(scene->primitives[0].normal_map_source.strength, 0.8);
  EXPECT_TRUE(SceneFeatures(*scene) & shading::kSceneNormalMaps);
  // A scene that gives a material keeps it.
  auto torus = LoadScene((kScenes / "torus-lowpoly.json").string());
  ASSERT_TRUE(torus) << torus.error();
  EXPECT_DOUBLE_EQ(torus->material.alpha.x, 0.05);
  // render --asset shades the asset with its own material too.
  auto alone = AssetScene(kScenes / "panel.gltf");
  ASSERT_TRUE(alone) << alone.error();
  EXPECT_NEAR(alone->material.alpha.x, alpha, 1e-9);
  EXPECT_NE(alone->primitives.at(0).normal_map, nullptr);
}

TEST(GeneratedAssets, MaterialOfMeshFollowsTheMetallicWorkflow) {
  MeshMaterial m;  // glTF's defaults: roughness 1, metallic 1, white
  auto d = MaterialOfMesh(m);
  ASSERT_TRUE(d) << d.error();
  EXPECT_DOUBLE_EQ(d->alpha.x, 1.0);
  EXPECT_EQ(d->f0, glm::dvec3(1));
  m.metallic = 0, m.roughness = 0.3, m.base_color = glm::dvec4(0.2, 0.4, 0.6, 1);
  d = MaterialOfMesh(m);
  ASSERT_TRUE(d) << d.error();
  EXPECT_NEAR(d->alpha.y, 0.09, 1e-12);
  EXPECT_EQ(d->f0, glm::dvec3(0.04));
  EXPECT_NEAR(d->albedo.y, 0.4, 1e-12);
  m.metallic_roughness_texture.file = kScenes / "no-such.png";
  d = MaterialOfMesh(m);
  ASSERT_FALSE(d);
  EXPECT_NE(d.error().find("no-such.png: the roughness texture cannot be read"), std::string::npos) << d.error();
  m.metallic_roughness_texture = {};
  m.normal_texture.encoded = std::make_shared<const std::vector<std::uint8_t>>();
  m.normal_texture.image = 3;
  NormalMapSource source;
  auto map = NormalMapOfMesh(m, &source);
  ASSERT_FALSE(map);
  EXPECT_NE(map.error().find("embedded (image 3)"), std::string::npos) << map.error();
}

}  // namespace
}  // namespace shimmer::scene
