// Tangent-space normal maps (seed 003_fd5f3d677171d779.txt) and the mip chain
// of what every normal-map filter reads: the unnormalised mean normal
// (Toksvig, vMF), LEAN's first and second slope moments (LEAN, CLEAN) and a
// baked Toksvig factor per level (Toksvig map).
//
// Conventions. A texel's normal n = (x, y, z) is in the tangent frame
// (tangent, bitangent, surface normal), z > 0. Its slope is t = n.xy / n.z,
// the same slope space as the renderer's half vector hpp = h.xy / h.z (seed
// 000), so a microfacet lobe centred on n is centred on t. `strength` scales
// the slope: n' = normalize(strength * n.x, strength * n.y, n.z).
#pragma once

#include <glm/glm.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "shimmer/core/result.h"

namespace shimmer::scene {

// Where a map comes from: exactly one of `file` and `procedural` is set.
struct NormalMapSource {
  std::string file;        // PNG (8 or 16 bit) or EXR (float), resolved by the caller
  std::string procedural;  // a name of ProceduralNormalMapNames()
  double strength = 1;     // slope scale, in [0, 10]
  bool operator==(const NormalMapSource&) const = default;
};

// One texel of one level: box-filter means over the level-0 texels it covers.
struct NormalMapTexel {
  glm::vec3 mean_normal{0, 0, 1};  // E[n], unnormalised: |E[n]| < 1 where the normals spread
  float toksvig_ft = 1;            // Toksvig factor baked at kToksvigFixedPower from a Gaussian-filtered level
  glm::vec2 b{0};                  // LEAN B = E[t]
  glm::vec3 m{0};                  // LEAN M = (E[t.x^2], E[t.y^2], E[t.x t.y])
};

struct NormalMapLevel {
  int width = 0, height = 0;
  std::vector<NormalMapTexel> texels;  // row-major, row 0 is v = 0
};

// Seed 003: "bake with a fixed power that gives reasonable contrast - around
// 100 seems to work well - and then convert later".
inline constexpr double kToksvigFixedPower = 100;
// Largest map side accepted (the packed chain must fit a storage buffer).
inline constexpr int kMaxNormalMapSide = 4096;

struct NormalMap {
  std::string name;                   // file name or procedural name, for messages
  std::vector<NormalMapLevel> levels;  // level 0 full resolution, halving to 1x1; sides are powers of two
};

// Built-in maps: the cases seed 003 discusses (isotropic bumps at a few
// frequencies, ridged / brushed, bumpy and flat areas side by side).
std::vector<std::string_view> ProceduralNormalMapNames();

// The map with its whole mip chain, built once per source and kept for the
// process (later calls with an equal source share it). Errors name the file
// (missing, unreadable, not a power of two, wrong channel count, a zero-length
// or downward normal) or the unknown procedural name.
Result<std::shared_ptr<const NormalMap>> LoadNormalMap(const NormalMapSource& source);

// The chain from level-0 normals (row-major, width x height, powers of two;
// each normal is normalised, z > 0 required).
Result<NormalMap> BuildNormalMap(std::string name, int width, int height, const std::vector<glm::dvec3>& normals);

}  // namespace shimmer::scene
