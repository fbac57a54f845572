// The per-tile primitive lists of the primary rays (tile_lists.h): every
// leaf whose box a tile's pixels can see is listed for that tile, in the
// BVH walk's order, so that a ray testing its tile's list finds traceScene's
// hit. (GpuRender.TileListsRenderWhatTheWalkRenders checks the frames.)
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "shimmer/renderer/scene.h"
#include "tile_lists.h"

namespace shimmer::render {
namespace {

struct Case {
  std::string scene;
  scene::CameraPath path;
  int frame;
};

// The pixel world point q projects to (scene.glsl's projectToPixel), or
// false when q is not in front of the camera.
bool ToPixel(const shading::CameraDesc& c, const glm::dvec3& q, glm::dvec2* pixel) {
  const glm::dvec3 v = q - c.pos;
  const double z = glm::dot(v, c.fwd);
  if (!(z > 1e-9)) return false;
  const double sx = c.tan_half_fov_y * double(c.width) / double(c.height), sy = c.tan_half_fov_y;
  *pixel = {(glm::dot(v, c.right) / (z * sx) + 1) * 0.5 * c.width, (1 - glm::dot(v, c.up) / (z * sy)) * 0.5 * c.height};
  return true;
}

class TileLists : public ::testing::TestWithParam<Case> {};

// Points spread through every leaf's box (the primitive, and so any point a
// ray can hit on it, lies inside): each one seen in the image must find its
// leaf in the list of the tile of the pixel it projects to, or that tile
// must walk the BVH. And each list follows the walk's order.
TEST_P(TileLists, ListEveryLeafATilesRaysCanReachInTheWalksOrder) {
  const Case& c = GetParam();
  // Not multiples of 8: the last tiles reach past the image's edge, where
  // the quads' helper lanes still trace.
  const int width = 158, height = 93;
  const auto loaded = scene::LoadScene(c.scene);
  ASSERT_TRUE(loaded) << loaded.error();
  const std::vector<glm::vec4> words = scene::PackScene(*loaded);
  const shading::CameraDesc camera = scene::CameraAt(c.path, loaded->rig, c.frame, 24.0, width, height);
  std::vector<std::int32_t> out(TileListWords(width, height));
  BuildTileLists(words, camera, width, height, out);
  const int tiles_x = (width + kTileSide - 1) / kTileSide, tiles = tiles_x * ((height + kTileSide - 1) / kTileSide);
  std::vector<std::set<int>> listed(tiles);
  int walking = 0;
  for (int t = 0; t < tiles; ++t) {
    const int first = out[2 * t], count = out[2 * t + 1];
    if (count < 0) {
      ++walking;
      continue;
    }
    ASSERT_LE(count, kMaxTilePrimitives);
    for (int i = 0; i < count; ++i) {
      if (i > 0) {
        EXPECT_LT(out[first + i - 1], out[first + i]) << "tile " << t << ": not in the walk's order";
      }
      listed[t].insert(out[first + i]);
    }
  }
  EXPECT_LT(walking, tiles) << "every tile walks the BVH: the lists do nothing";
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  const int nodes = int(words[0].y);
  int seen = 0;
  for (int n = 0; n < nodes; ++n) {
    const glm::vec4 w0 = words[1 + 2 * n], w1 = words[2 + 2 * n];
    if (int(w1.w) - 1 < 0) continue;  // interior
    for (int k = 0; k < 400; ++k) {
      const glm::dvec3 q{w0.x + u(rng) * (w1.x - w0.x), w0.y + u(rng) * (w1.y - w0.y), w0.z + u(rng) * (w1.z - w0.z)};
      glm::dvec2 pixel;
      if (!ToPixel(camera, q, &pixel) || pixel.x < 0 || pixel.y < 0 || pixel.x >= tiles_x * kTileSide ||
          pixel.y >= tiles * kTileSide / tiles_x)
        continue;
      ++seen;
      const int t = int(pixel.y) / kTileSide * tiles_x + int(pixel.x) / kTileSide;
      if (out[2 * t + 1] >= 0) {
        EXPECT_TRUE(listed[t].count(n)) << "leaf " << n << " seen in tile " << t << " but not listed";
      }
    }
  }
  EXPECT_GT(seen, 0);
}

INSTANTIATE_TEST_SUITE_P(Scenes, TileLists,
                         ::testing::Values(Case{"sphere-field", scene::CameraPath::kOrbit, 0},
                                           Case{"sphere-field", scene::CameraPath::kDolly, 20},
                                           Case{"wires", scene::CameraPath::kOrbit, 5},
                                           Case{"sg-sphere-field", scene::CameraPath::kVrJitter, 3}),
                         [](const auto& info) {
                           std::string name = info.param.scene + "_" + std::to_string(info.index);
                           for (char& ch : name) {
                             if (ch == '-') ch = '_';
                           }
                           return name;
                         });

// A camera inside a leaf's box sees it in every direction: every tile lists
// it (or walks).
TEST(TileLists, ABoxAroundTheCameraReachesEveryTile) {
  scene::Scene s;
  s.primitives.resize(2);  // spheres
  s.primitives[0].radius = 2.0;
  s.primitives[1].a = {5, 0, 0};
  s.primitives[1].radius = 0.5;
  const std::vector<glm::vec4> words = scene::PackScene(s);
  shading::CameraDesc camera;
  camera.pos = {0, 0, 1};  // inside the first sphere's box
  camera.width = 64, camera.height = 64;
  std::vector<std::int32_t> out(TileListWords(64, 64));
  BuildTileLists(words, camera, 64, 64, out);
  int leaf_of_big = -1;
  for (int n = 0; n < int(words[0].y); ++n)
    if (int(words[2 + 2 * n].w) - 1 >= 0 && words[2 + 2 * n].x - words[1 + 2 * n].x > 3.9f) leaf_of_big = n;
  ASSERT_GE(leaf_of_big, 0);
  for (int t = 0; t < 64; ++t) {
    const int first = out[2 * t], count = out[2 * t + 1];
    if (count < 0) continue;
    bool found = false;
    for (int i = 0; i < count; ++i) found = found || out[first + i] == leaf_of_big;
    EXPECT_TRUE(found) << "tile " << t;
  }
}

// A 60-pixel-wide image has a partial last column of tiles (pixels 56-63):
// its invocations past the edge (60-63) still trace, as the quads' helper
// lanes whose samples give their neighbours' derivatives. A sphere seen
// only there must be in that tile's list.
TEST(TileLists, ABoxSeenOnlyPastTheImagesEdgeIsListedForItsPartialTile) {
  shading::CameraDesc camera;  // at (0, 0, 5) looking down -z, tan(fov/2) = 0.4
  camera.width = 60, camera.height = 40;
  // The ray through pixel (62.5, 20.5) meets z = 0 at x = nx sx 5.
  const double sx = camera.tan_half_fov_y * 60.0 / 40.0, nx = 2 * 62.5 / 60 - 1;
  scene::Scene s;
  s.primitives.resize(1);  // a sphere
  s.primitives[0].a = {nx * sx * 5, -(2 * 20.5 / 40 - 1) * camera.tan_half_fov_y * 5, 0};
  s.primitives[0].radius = 0.01;
  const std::vector<glm::vec4> words = scene::PackScene(s);
  glm::dvec2 pixel;
  ASSERT_TRUE(ToPixel(camera, s.primitives[0].a, &pixel));
  ASSERT_NEAR(pixel.x, 62.5, 1e-9);  // past the edge, inside the partial tile
  std::vector<std::int32_t> out(TileListWords(60, 40));
  BuildTileLists(words, camera, 60, 40, out);
  const int t = 2 * 8 + 7;  // tile row 2 (pixels 16-23), column 7 (56-63)
  ASSERT_EQ(out[2 * t + 1], 1);
  EXPECT_EQ(out[out[2 * t]], 0);  // the one leaf, node 0
}

}  // namespace
}  // namespace shimmer::render
