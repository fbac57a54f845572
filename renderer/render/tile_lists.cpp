#include "tile_lists.h"

#include <algorithm>
#include <cmath>

namespace shimmer::render {

namespace {

int TilesAlong(int pixels) { return (pixels + kTileSide - 1) / kTileSide; }

// Tile t's header: no list, the BVH walk.
void MarkWalk(int t, std::span<std::int32_t> out) { out[2 * t] = 0, out[2 * t + 1] = -1; }

// The pixel rectangle a box's projection covers, widened by a pixel (the
// kernel's float camera against this double one, and a reference sample's
// ray anywhere in its pixel); `everywhere` when a corner is not in front of
// the camera, where the projection is unbounded.
struct PixelRect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool everywhere = false;
};

PixelRect Project(const glm::dvec3& lo, const glm::dvec3& hi, const shading::CameraDesc& c) {
  const double sx = c.tan_half_fov_y * double(c.width) / double(c.height), sy = c.tan_half_fov_y;
  PixelRect r;
  r.x0 = r.y0 = 1e300;
  r.x1 = r.y1 = -1e300;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 q{(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z};
    const glm::dvec3 v = q - c.pos;
    const double z = glm::dot(v, c.fwd);
    if (!(z > 1e-6 * (glm::length(v) + 1e-6))) {
      r.everywhere = true;
      return r;
    }
    // scene.glsl's projectToPixel.
    const double px = (glm::dot(v, c.right) / (z * sx) + 1) * 0.5 * c.width;
    const double py = (1 - glm::dot(v, c.up) / (z * sy)) * 0.5 * c.height;
    r.x0 = std::min(r.x0, px), r.x1 = std::max(r.x1, px);
    r.y0 = std::min(r.y0, py), r.y1 = std::max(r.y1, py);
  }
  r.x0 -= 1, r.y0 -= 1, r.x1 += 1, r.y1 += 1;
  return r;
}

}  // namespace

std::size_t TileListWords(int width, int height) {
  const std::size_t tiles = std::size_t(TilesAlong(width)) * TilesAlong(height);
  return tiles * (2 + kMaxTilePrimitives);
}

void WalkEveryTile(int width, int height, std::span<std::int32_t> out) {
  for (int t = 0; t < TilesAlong(width) * TilesAlong(height); ++t) MarkWalk(t, out);
}

void BuildTileLists(std::span<const glm::vec4> scene_words, const shading::CameraDesc& camera, int width,
                    int height, std::span<std::int32_t> out) {
  const int tiles_x = TilesAlong(width), tiles_y = TilesAlong(height), tiles = tiles_x * tiles_y;
  // Each tile's leaves (their node indices), in node order: the walk's.
  std::vector<std::vector<std::int32_t>> listed(static_cast<std::size_t>(tiles));
  const int nodes = scene_words.empty() ? 0 : int(scene_words[0].y);
  for (int n = 0; n < nodes; ++n) {
    const glm::vec4 w0 = scene_words[1 + 2 * n], w1 = scene_words[2 + 2 * n];
    const int prim = int(w1.w) - 1;
    if (prim < 0) continue;  // interior
    // The box as the kernel has it (float), widened for the rounding of
    // the kernel's own intersections.
    const glm::dvec3 lo{w0.x, w0.y, w0.z}, hi{w1.x, w1.y, w1.z};
    const glm::dvec3 pad = (glm::abs(lo) + glm::abs(hi) + 1.0) * 1e-6;
    const PixelRect r = Project(lo - pad, hi + pad, camera);
    int tx0 = 0, ty0 = 0, tx1 = tiles_x - 1, ty1 = tiles_y - 1;
    if (!r.everywhere) {
      // The tiles' whole extent: past the image's edge, a partial tile's
      // invocations still trace (the quads' helper lanes, whose samples
      // give their neighbours' derivatives).
      if (r.x1 < 0 || r.y1 < 0 || r.x0 > tiles_x * kTileSide || r.y0 > tiles_y * kTileSide) continue;
      tx0 = std::max(0, int(std::floor(r.x0 / kTileSide)));
      ty0 = std::max(0, int(std::floor(r.y0 / kTileSide)));
      tx1 = std::min(tiles_x - 1, int(std::floor(r.x1 / kTileSide)));
      ty1 = std::min(tiles_y - 1, int(std::floor(r.y1 / kTileSide)));
    }
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) {
        auto& list = listed[static_cast<std::size_t>(ty) * tiles_x + tx];
        if (list.size() <= std::size_t(kMaxTilePrimitives)) list.push_back(n);
      }
  }
  std::int32_t next = 2 * tiles;
  for (int t = 0; t < tiles; ++t) {
    const auto& list = listed[static_cast<std::size_t>(t)];
    if (list.size() > std::size_t(kMaxTilePrimitives)) {
      MarkWalk(t, out);
      continue;
    }
    out[2 * t] = next;
    out[2 * t + 1] = static_cast<std::int32_t>(list.size());
    std::copy(list.begin(), list.end(), out.begin() + next);
    next += static_cast<std::int32_t>(list.size());
  }
}

}  // namespace shimmer::render
