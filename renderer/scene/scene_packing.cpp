// A scene as the kernel reads it: its primitives, normal maps and BVH packed
// into vec4 words (scene.glsl's layout), and the feature mask that
// specialises the kernel.
#include "shimmer/renderer/scene.h"

#include <algorithm>
#include <numeric>

namespace shimmer::scene {

namespace {

// --- BVH --------------------------------------------------------------------

struct Box {
  glm::dvec3 lo{1e300}, hi{-1e300};
  void Add(const Box& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
};

Box Bounds(const Primitive& p) {
  Box b;
  glm::dvec3 r(p.radius);
  if (p.type == Primitive::Type::kSphere) return {p.a - r, p.a + r};
  if (p.type == Primitive::Type::kMesh) return {p.a, p.b};
  b.lo = glm::min(p.a, p.b) - r;
  b.hi = glm::max(p.a, p.b) + r;
  return b;
}

struct PrimNode {
  Box box;
  int skip = 0;   // the node after this subtree
  int prim = -1;  // a leaf's one primitive; -1: interior
};

// Median split on the widest centroid axis, nodes appended in depth-first
// order (scene.glsl walks them without a stack).
void BuildNode(std::vector<PrimNode>& nodes, std::vector<int>& order, int begin, int end,
               const std::vector<Primitive>& prims) {
  const int index = static_cast<int>(nodes.size());
  nodes.emplace_back();
  Box box, centroids;
  for (int i = begin; i < end; ++i) {
    Box b = Bounds(prims[order[i]]);
    box.Add(b);
    glm::dvec3 c = (b.lo + b.hi) * 0.5;
    centroids.Add({c, c});
  }
  nodes[index].box = box;
  if (end - begin == 1) {
    nodes[index].prim = begin;
  } else {
    glm::dvec3 ext = centroids.hi - centroids.lo;
    int axis = ext.x > ext.y ? (ext.x > ext.z ? 0 : 2) : (ext.y > ext.z ? 1 : 2);
    int mid = (begin + end) / 2;
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, [&](int a, int b) {
      Box ba = Bounds(prims[a]), bb = Bounds(prims[b]);
      return ba.lo[axis] + ba.hi[axis] < bb.lo[axis] + bb.hi[axis];
    });
    BuildNode(nodes, order, begin, mid, prims);
    BuildNode(nodes, order, mid, end, prims);
  }
  nodes[index].skip = static_cast<int>(nodes.size());
}

// One mesh at word `base`, its normal map's header at `map` and its
// roughness texture's at `roughness` (0: none).
void PackMesh(const PlacedMesh& placed, int base, int map, int roughness, std::vector<glm::vec4>& words) {
  const TriangleBvh& bvh = placed.bvh;
  const TriangleMesh& mesh = placed.mesh;
  const int nodes = static_cast<int>(bvh.nodes().size());
  const int triangles = static_cast<int>(bvh.triangle_order().size());
  const int first_node = base + 1, first_triangle = first_node + 2 * nodes,
            first_vertex = first_triangle + 3 * triangles;
  words.push_back({float(nodes), float(first_node), float(first_triangle), float(triangles)});
  for (const BvhNode& n : bvh.nodes()) {
    words.push_back({n.lo.x, n.lo.y, n.lo.z, float(n.offset)});
    words.push_back({n.hi.x, n.hi.y, n.hi.z, float(n.count)});
  }
  for (int j = 0; j < triangles; ++j)
    for (int c = 0; c < 3; ++c) {
      const glm::vec3 p = bvh.triangle_vertices()[std::size_t(3 * j + c)];
      const std::uint32_t v = mesh.indices[3 * std::size_t(bvh.triangle_order()[std::size_t(j)]) + std::size_t(c)];
      words.push_back({p.x, p.y, p.z, float(first_vertex + 3 * static_cast<int>(v))});
    }
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const glm::vec3 n = mesh.normals[v];
    const glm::vec4 t = mesh.tangents[v];
    const glm::vec2 uv = mesh.uv0[v];
    words.push_back({n.x, n.y, n.z, uv.x});
    words.push_back(t);
    words.push_back({uv.y, float(map), float(roughness), 0.0f});
  }
}

glm::vec4 PrimWord0(const Primitive& p) {
  return {float(static_cast<int>(p.type)), float(p.radius), float(p.bump_slope), float(p.bump_frequency)};
}

}  // namespace

int SceneFeatures(const Scene& scene) {
  using namespace shading;
  int mask = 0;
  for (const Primitive& p : scene.primitives) {
    if (p.normal_map) mask |= kSceneNormalMaps;
    if (p.type == Primitive::Type::kSphere) mask |= kSceneSpheres;
    if (p.type == Primitive::Type::kCapsule) mask |= kSceneCapsules;
    if (p.type == Primitive::Type::kPlane) mask |= kScenePlanes | (p.bump_slope != 0 ? kSceneBumps : 0);
    if (p.type == Primitive::Type::kMesh) mask |= kSceneMeshes;
    if (p.roughness_map) mask |= kSceneRoughnessMaps;
  }
  if (scene.light.shadows) mask |= kSceneShadows;
  return mask;
}

std::vector<glm::vec4> PackScene(const Scene& scene) {
  std::vector<Primitive> bounded, unbounded;
  for (const Primitive& p : scene.primitives) (p.type == Primitive::Type::kPlane ? unbounded : bounded).push_back(p);
  std::vector<int> order(bounded.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<PrimNode> nodes;
  if (!bounded.empty()) BuildNode(nodes, order, 0, static_cast<int>(bounded.size()), bounded);
  const int first_prim_word = 1 + 2 * static_cast<int>(nodes.size());
  std::vector<glm::vec4> words;
  words.push_back({float(bounded.size()), float(nodes.size()), float(first_prim_word), float(unbounded.size())});
  for (const PrimNode& n : nodes) {
    words.push_back({float(n.box.lo.x), float(n.box.lo.y), float(n.box.lo.z), float(n.skip)});
    words.push_back({float(n.box.hi.x), float(n.box.hi.y), float(n.box.hi.z), float(n.prim + 1)});  // 0: interior
  }
  std::vector<const Primitive*> packed;
  for (int i : order) packed.push_back(&bounded[i]);
  for (const Primitive& p : unbounded) packed.push_back(&p);
  // Normal maps (normal_map.glsl's layout): one header per mapped primitive
  // (its scale is its own), then each map's texels once however many
  // primitives share it.
  std::vector<const NormalMap*> maps;
  std::vector<int> header_word(packed.size(), 0);
  int next = first_prim_word + 3 * static_cast<int>(packed.size());
  for (std::size_t k = 0; k < packed.size(); ++k) {
    const NormalMap* map = packed[k]->normal_map.get();
    if (!map) continue;
    header_word[k] = next;
    next += 2 + static_cast<int>(map->levels.size());
    if (std::find(maps.begin(), maps.end(), map) == maps.end()) maps.push_back(map);
  }
  std::vector<std::vector<int>> level_word(maps.size());
  for (std::size_t m = 0; m < maps.size(); ++m)
    for (const NormalMapLevel& level : maps[m]->levels) {
      level_word[m].push_back(next);
      next += 3 * static_cast<int>(level.texels.size());
    }
  // Meshes (scene.glsl's layout) after the texels.
  std::vector<int> mesh_word(packed.size(), 0);
  for (std::size_t k = 0; k < packed.size(); ++k)
    if (packed[k]->mesh) {
      mesh_word[k] = next;
      next += static_cast<int>(PackedMeshWords(*packed[k]->mesh));
    }
  // Roughness textures (scene.glsl's layout) after the meshes.
  std::vector<int> roughness_word(packed.size(), 0);
  for (std::size_t k = 0; k < packed.size(); ++k)
    if (packed[k]->mesh && packed[k]->roughness_map) {
      roughness_word[k] = next;
      next += static_cast<int>(PackedRoughnessWords(*packed[k]->roughness_map));
    }
  for (std::size_t k = 0; k < packed.size(); ++k) {
    const Primitive& p = *packed[k];
    words.push_back(PrimWord0(p));
    words.push_back({float(p.a.x), float(p.a.y), float(p.a.z), float(header_word[k])});
    words.push_back({float(p.b.x), float(p.b.y), float(p.b.z), float(mesh_word[k])});
  }
  for (std::size_t k = 0; k < packed.size(); ++k) {
    const NormalMap* map = packed[k]->normal_map.get();
    if (!map) continue;
    const std::size_t m = std::size_t(std::find(maps.begin(), maps.end(), map) - maps.begin());
    const NormalMapLevel& top = map->levels.front();
    words.push_back({float(map->levels.size()), float(top.width), float(top.height), 0.0f});
    const glm::dvec2 scale = packed[k]->normal_map_scale;
    words.push_back({float(scale.x), float(scale.y), 0.0f, 0.0f});
    for (std::size_t l = 0; l < map->levels.size(); ++l)
      words.push_back({float(level_word[m][l]), float(map->levels[l].width), float(map->levels[l].height), 0.0f});
  }
  for (const NormalMap* map : maps)
    for (const NormalMapLevel& level : map->levels)
      for (const NormalMapTexel& t : level.texels) {
        words.push_back({t.mean_normal.x, t.mean_normal.y, t.mean_normal.z, t.toksvig_ft});
        words.push_back({t.b.x, t.b.y, t.m.x, t.m.y});
        words.push_back({t.m.z, 0.0f, 0.0f, 0.0f});
      }
  for (std::size_t k = 0; k < packed.size(); ++k)
    if (packed[k]->mesh) PackMesh(*packed[k]->mesh, mesh_word[k], header_word[k], roughness_word[k], words);
  for (std::size_t k = 0; k < packed.size(); ++k) {
    if (!roughness_word[k]) continue;
    const RoughnessMap& map = *packed[k]->roughness_map;
    words.push_back({float(map.width), float(map.height), float(roughness_word[k] + 1), 0.0f});
    for (std::size_t i = 0; i < map.alpha_factor.size(); i += 4) {
      glm::vec4 w{0.0f};
      for (std::size_t j = 0; j < 4 && i + j < map.alpha_factor.size(); ++j) w[int(j)] = map.alpha_factor[i + j];
      words.push_back(w);
    }
  }
  return words;
}

}  // namespace shimmer::scene
