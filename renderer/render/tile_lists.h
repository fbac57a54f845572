// The primitives each 8x8 pixel tile's camera rays can reach, listed per
// frame on the CPU, so that a pixel's primary ray tests a few primitives
// instead of walking the scene's BVH (render.comp, traceTile and
// tileCandidates). A workgroup is one tile: all its invocations read the same
// list, in the same order, with no divergence between them.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "shimmer/shading/shading.h"

namespace shimmer::render {

// The tile side in pixels: a workgroup's (render.comp's 8x8 invocations).
inline constexpr int kTileSide = 8;
// A tile that reaches more bounded primitives than this walks the BVH
// instead (its count is -1): past a few dozen, the walk is the cheaper test.
inline constexpr int kMaxTilePrimitives = 32;

// Words of the tile buffer for a width x height image: per tile (row-major,
// tiles of kTileSide) its list's first word and its count, then the lists.
std::size_t TileListWords(int width, int height);

// Fills `out` (TileListWords words) for the scene packed as `scene_words`
// (scene_packing.cpp's layout: the BVH's leaves are the bounded primitives)
// seen by `camera`. A tile lists the node index of every leaf whose box's
// projection, widened by a pixel, reaches the tile (all of its 8x8 pixels,
// those past the image's edge too), in depth-first order
// (the order traceScene meets them, so ties resolve alike); a box not wholly
// in front of the camera reaches every tile. Unbounded primitives (planes)
// are not listed: every ray tests them first, as in traceScene.
void BuildTileLists(std::span<const glm::vec4> scene_words, const shading::CameraDesc& camera, int width,
                    int height, std::span<std::int32_t> out);

// Fills `out` (TileListWords words) so that every tile walks the BVH (the
// renderer's test hook walk_instead_of_tile_lists).
void WalkEveryTile(int width, int height, std::span<std::int32_t> out);

}  // namespace shimmer::render
