// A bounding volume hierarchy over a triangle mesh, built on the CPU with the
// binned surface area heuristic and flattened for a GPU, with a CPU closest-
// hit query and the brute-force query the tests hold it to.
//
// Layout (what a kernel reads): `nodes` in depth-first order, root first,
// 32 bytes each (std430-compatible: vec3 + uint, vec3 + uint):
//   interior (count == 0): the left child is the next node, index + 1;
//                          `offset` is the right child's index.
//   leaf (count 1..4):     triangles [offset, offset + count) of the
//                          permuted order, i.e. of `triangle_vertices`
//                          (three corners per triangle) and `triangle_order`
//                          (each one's index in the mesh).
// Zero-area triangles (ZeroAreaTriangle) are left out: no ray can hit them.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/renderer/triangle_mesh.h"

namespace shimmer::scene {

struct BvhNode {
  glm::vec3 lo{0};
  std::uint32_t offset = 0;  // interior: right child's index; leaf: first triangle
  glm::vec3 hi{0};
  std::uint32_t count = 0;  // 0: interior; otherwise the leaf's triangle count
};
static_assert(sizeof(BvhNode) == 32);

struct BvhBuildOptions {
  int bins = 32;               // SAH bins along the longest axis of the centroids' bounds, 2..256
  int max_leaf_triangles = 4;  // 1..255
};

// The nearest hit. The hit point is (1 - b.x - b.y) v0 + b.x v1 + b.y v2 of
// the triangle's corners in the mesh's order.
struct RayHit {
  float t = 0;
  std::uint32_t triangle = 0;  // the triangle's index in the mesh (indices[3 * triangle ...])
  glm::vec2 barycentrics{0};
};

// The watertight ray/triangle test of Woop, Benthin and Wald 2013
// ("Watertight Ray/Triangle Intersection", JCGT 2(1)): the ray's space sheared
// so that it runs along +z, edge functions in float with a double fallback
// for the exact-zero cases, so a ray through a shared edge or vertex hits at
// least one of the triangles and no ray slips between them. Both faces hit.
// A hit needs 0 < t < tmax; a zero or non-finite direction never hits, nor
// does any case that would give a NaN. Zero-area triangles are the caller's
// to leave out, as the BVH and IntersectBruteForce do: rounding in the shear
// can give collinear corners a tiny area and so a spurious hit.
class RayTriangleTest {
 public:
  RayTriangleTest(const glm::vec3& origin, const glm::vec3& direction);
  bool valid() const { return valid_; }
  std::optional<RayHit> Intersect(const glm::vec3& v0, const glm::vec3& v1, const glm::vec3& v2, float tmax) const;

 private:
  glm::vec3 origin_;
  int kx_ = 0, ky_ = 1, kz_ = 2;
  float sx_ = 0, sy_ = 0, sz_ = 0;
  bool valid_ = false;
};

class TriangleBvh {
 public:
  // Errors: an index count not a multiple of 3, an index out of range, a
  // non-finite position, more than 2^32 - 1 triangles, bad options.
  static Result<TriangleBvh> Build(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                                   const BvhBuildOptions& options = {});
  static Result<TriangleBvh> Build(const TriangleMesh& mesh, const BvhBuildOptions& options = {}) {
    return Build(mesh.positions, mesh.indices, options);
  }

  // The nearest hit with 0 < t < tmax. Equal t: the lower triangle index,
  // so the answer does not depend on the traversal order.
  std::optional<RayHit> Intersect(const glm::vec3& origin, const glm::vec3& direction, float tmax) const;

  const std::vector<BvhNode>& nodes() const { return nodes_; }
  const std::vector<glm::vec3>& triangle_vertices() const { return vertices_; }
  const std::vector<std::uint32_t>& triangle_order() const { return order_; }
  std::size_t zero_area_triangles() const { return zero_area_; }
  int depth() const { return depth_; }
  // The SAH cost of the tree (traversal 1, one triangle test 1, relative to
  // the root's area): to compare builds.
  double SahCost() const;

 private:
  std::vector<BvhNode> nodes_;
  std::vector<glm::vec3> vertices_;
  std::vector<std::uint32_t> order_;
  std::size_t zero_area_ = 0;
  int depth_ = 0;
};

// Every triangle tested, for the tests: the same answer as
// TriangleBvh::Intersect (same test, same tie rule). Indices must be valid.
std::optional<RayHit> IntersectBruteForce(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                                          const glm::vec3& origin, const glm::vec3& direction, float tmax);

}  // namespace shimmer::scene
