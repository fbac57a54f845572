// The triangle BVH (CPU only): its flattened layout, and its closest hits
// against brute force on 10^5 random rays per mesh (a triangle soup with
// zero-area triangles, a tessellated sphere, a thin long cable), rays aimed
// at shared vertices, rays that miss, and the watertight triangle test.
#include <gtest/gtest.h>

#include <glm/gtc/constants.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "shimmer/renderer/triangle_bvh.h"

namespace shimmer::scene {
namespace {

constexpr int kRays = 100000;

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
};

// Random triangles in [-1, 1]^3 of random sizes; every tenth has zero area
// (two equal corners, three equal corners, or three exactly collinear ones).
Mesh Soup(int triangles, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> unit(-1, 1), size(0.01f, 0.3f);
  Mesh m;
  for (int i = 0; i < triangles; ++i) {
    const glm::vec3 a(unit(random), unit(random), unit(random));
    const float s = size(random);
    glm::vec3 b = a + s * glm::vec3(unit(random), unit(random), unit(random));
    glm::vec3 c = a + s * glm::vec3(unit(random), unit(random), unit(random));
    if (i % 10 == 3) b = a;
    if (i % 10 == 6) b = c = a;
    if (i % 10 == 9) {  // on a line along x: y and z stay exactly equal
      b = a + glm::vec3(s, 0, 0);
      c = a + glm::vec3(2 * s, 0, 0);
    }
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), {a, b, c});
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
  }
  return m;
}

// A UV sphere of the given radius with shared vertices and one per pole.
Mesh Sphere(int rings, int segments, float radius = 1) {
  Mesh m;
  m.positions.push_back({0, radius, 0});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double theta = glm::pi<double>() * r / rings, phi = 2 * glm::pi<double>() * s / segments;
      m.positions.push_back(
          radius * glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)));
    }
  m.positions.push_back({0, -radius, 0});
  auto at = [&](int r, int s) { return static_cast<std::uint32_t>(1 + (r - 1) * segments + s % segments); };
  const auto south = static_cast<std::uint32_t>(m.positions.size() - 1);
  for (int s = 0; s < segments; ++s) {
    m.indices.insert(m.indices.end(), {0, at(1, s + 1), at(1, s)});
    for (int r = 1; r + 1 < rings; ++r)
      m.indices.insert(m.indices.end(),
                       {at(r, s), at(r, s + 1), at(r + 1, s + 1), at(r, s), at(r + 1, s + 1), at(r + 1, s)});
    m.indices.insert(m.indices.end(), {at(rings - 1, s), at(rings - 1, s + 1), south});
  }
  return m;
}

// A tube of radius 0.002 along a sagging 10-unit curve: long, thin
// triangles whose boxes overlap a lot.
glm::vec3 CableAxis(float x) { return {x, 0.3f * (x * x / 25 - 1), 0}; }

Mesh Cable(int segments, int sides) {
  Mesh m;
  for (int i = 0; i <= segments; ++i) {
    const float x = -5 + 10.0f * i / segments;
    for (int k = 0; k < sides; ++k) {
      const float a = 2 * glm::pi<float>() * k / sides;
      m.positions.push_back(CableAxis(x) + 0.002f * glm::vec3(0, std::cos(a), std::sin(a)));
    }
  }
  for (int i = 0; i < segments; ++i)
    for (int k = 0; k < sides; ++k) {
      const auto p = static_cast<std::uint32_t>(i * sides + k),
                 q = static_cast<std::uint32_t>(i * sides + (k + 1) % sides);
      const auto n = static_cast<std::uint32_t>(sides);
      m.indices.insert(m.indices.end(), {p, q, q + n, p, q + n, p + n});
    }
  return m;
}

struct Ray {
  glm::vec3 origin, direction;
};

// Origins around the mesh, aimed at `target(random)`; one ray in five points
// anywhere (most of those miss).
template <class Target>
std::vector<Ray> Rays(int n, float distance, unsigned seed, Target target) {
  std::mt19937 random(seed);
  std::normal_distribution<float> normal;
  std::vector<Ray> rays;
  for (int i = 0; i < n; ++i) {
    const glm::vec3 origin = distance * glm::normalize(glm::vec3(normal(random), normal(random), normal(random)));
    const glm::vec3 direction =
        i % 5 == 4 ? glm::vec3(normal(random), normal(random), normal(random)) : target(random) - origin;
    rays.push_back({origin, direction});
  }
  return rays;
}

// Every ray: the same triangle, t within 1e-5 relative, or both miss.
// Returns how many hit.
int CompareWithBruteForce(const Mesh& mesh, const std::vector<Ray>& rays) {
  Result<TriangleBvh> bvh = TriangleBvh::Build(mesh.positions, mesh.indices);
  EXPECT_TRUE(bvh.ok()) << bvh.error();
  if (!bvh) return 0;
  int hits = 0, mismatches = 0;
  for (const Ray& ray : rays) {
    const float tmax = std::numeric_limits<float>::infinity();
    const std::optional<RayHit> fast = bvh->Intersect(ray.origin, ray.direction, tmax);
    const std::optional<RayHit> slow =
        IntersectBruteForce(mesh.positions, mesh.indices, ray.origin, ray.direction, tmax);
    hits += slow.has_value();
    const bool same = fast.has_value() == slow.has_value() &&
                      (!fast || (fast->triangle == slow->triangle && std::abs(fast->t - slow->t) <= 1e-5f * slow->t));
    if (!same && ++mismatches <= 5)
      ADD_FAILURE() << "ray from (" << ray.origin.x << ", " << ray.origin.y << ", " << ray.origin.z << ") along ("
                    << ray.direction.x << ", " << ray.direction.y << ", " << ray.direction.z << "): BVH "
                    << (fast ? std::to_string(fast->triangle) + " at " + std::to_string(fast->t) : "miss")
                    << ", brute force "
                    << (slow ? std::to_string(slow->triangle) + " at " + std::to_string(slow->t) : "miss");
  }
  EXPECT_EQ(mismatches, 0);
  return hits;
}

// The layout of triangle_bvh.h: depth-first, left child next, right child
// after the left subtree, leaves of 1..4 triangles, every triangle with area
// exactly once, and every box exactly the bounds of its children or corners.
void CheckLayout(const Mesh& mesh, const TriangleBvh& bvh) {
  const std::vector<BvhNode>& nodes = bvh.nodes();
  std::vector<int> seen(mesh.indices.size() / 3, 0);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const BvhNode& n = nodes[i];
    if (n.count == 0) {
      ASSERT_LT(i + 1, nodes.size());
      ASSERT_GT(n.offset, i + 1);
      ASSERT_LT(n.offset, nodes.size());
      // Tight: exactly its children's union (the build bounds a range by
      // its split's bins, not by a scan of its triangles).
      EXPECT_EQ(n.lo, glm::min(nodes[i + 1].lo, nodes[n.offset].lo)) << "node " << i;
      EXPECT_EQ(n.hi, glm::max(nodes[i + 1].hi, nodes[n.offset].hi)) << "node " << i;
      continue;
    }
    ASSERT_LE(n.count, 4u);
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    for (std::uint32_t k = n.offset; k < n.offset + n.count; ++k) {
      const std::uint32_t t = bvh.triangle_order()[k];
      ++seen[t];
      for (int c = 0; c < 3; ++c) {
        const glm::vec3& v = bvh.triangle_vertices()[3 * k + c];
        EXPECT_EQ(v, mesh.positions[mesh.indices[3 * t + c]]);
        lo = glm::min(lo, v), hi = glm::max(hi, v);
      }
    }
    EXPECT_EQ(n.lo, lo) << "leaf " << i;  // its corners' bounds, exactly
    EXPECT_EQ(n.hi, hi) << "leaf " << i;
  }
  std::size_t zero = 0;
  for (std::size_t t = 0; t < seen.size(); ++t) {
    const bool zero_area =
        ZeroAreaTriangle(mesh.positions[mesh.indices[3 * t]], mesh.positions[mesh.indices[3 * t + 1]],
                         mesh.positions[mesh.indices[3 * t + 2]]);
    zero += zero_area;
    EXPECT_EQ(seen[t], zero_area ? 0 : 1) << "triangle " << t;
  }
  EXPECT_EQ(bvh.zero_area_triangles(), zero);
  EXPECT_EQ(bvh.triangle_order().size() + zero, seen.size());
}

TEST(TriangleBvh, SoupWithZeroAreaTrianglesMatchesBruteForce) {
  const Mesh soup = Soup(1500, 1);
  Result<TriangleBvh> bvh = TriangleBvh::Build(soup.positions, soup.indices);
  ASSERT_TRUE(bvh.ok()) << bvh.error();
  EXPECT_EQ(bvh->zero_area_triangles(), 450u);
  CheckLayout(soup, *bvh);
  std::uniform_real_distribution<float> unit(-1, 1);
  const int hits = CompareWithBruteForce(
      soup, Rays(kRays, 4, 2, [&](std::mt19937& r) { return glm::vec3(unit(r), unit(r), unit(r)); }));
  EXPECT_GT(hits, kRays / 4);
  EXPECT_LT(hits, kRays);
}

TEST(TriangleBvh, SphereMatchesBruteForceIncludingRaysThroughVertices) {
  const Mesh sphere = Sphere(32, 64);
  Result<TriangleBvh> bvh = TriangleBvh::Build(sphere.positions, sphere.indices);
  ASSERT_TRUE(bvh.ok()) << bvh.error();
  CheckLayout(sphere, *bvh);
  std::uniform_real_distribution<float> unit(-1, 1);
  std::uniform_int_distribution<std::size_t> vertex(0, sphere.positions.size() - 1);
  CompareWithBruteForce(
      sphere, Rays(kRays, 3, 3, [&](std::mt19937& r) { return 0.9f * glm::vec3(unit(r), unit(r), unit(r)); }));
  // Aimed exactly at vertices, where up to six triangles meet: the tie rule
  // makes the BVH give brute force's triangle, and watertightness a hit.
  const std::vector<Ray> at_vertices = Rays(10000, 3, 4, [&](std::mt19937& r) { return sphere.positions[vertex(r)]; });
  const int hits = CompareWithBruteForce(sphere, at_vertices);
  EXPECT_GE(hits, 8000);
}

TEST(TriangleBvh, ThinCableMatchesBruteForce) {
  const Mesh cable = Cable(400, 6);
  Result<TriangleBvh> bvh = TriangleBvh::Build(cable.positions, cable.indices);
  ASSERT_TRUE(bvh.ok()) << bvh.error();
  CheckLayout(cable, *bvh);
  std::uniform_real_distribution<float> along(-5, 5), offset(-0.003f, 0.003f);
  const int hits = CompareWithBruteForce(cable, Rays(kRays, 8, 5, [&](std::mt19937& r) {
                                           return CableAxis(along(r)) + glm::vec3(0, offset(r), offset(r));
                                         }));
  EXPECT_GT(hits, kRays / 4);
}

TEST(TriangleBvh, HitPointsAndRaysThatMiss) {
  const Mesh sphere = Sphere(16, 32, 2);
  Result<TriangleBvh> bvh = TriangleBvh::Build(sphere.positions, sphere.indices);
  ASSERT_TRUE(bvh.ok()) << bvh.error();
  std::mt19937 random(6);
  std::normal_distribution<float> normal;
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 out = glm::normalize(glm::vec3(normal(random), normal(random), normal(random)));
    const glm::vec3 origin = 5.0f * out;
    // Away from the sphere, and past it: misses.
    EXPECT_FALSE(bvh->Intersect(origin, out, 1e30f)) << i;
    EXPECT_FALSE(bvh->Intersect(origin, glm::cross(out, glm::vec3(0.36f, 0.48f, 0.8f)), 1e30f)) << i;
    // Toward the centre: a hit before tmax, none when tmax is short of it.
    const std::optional<RayHit> hit = bvh->Intersect(origin, -out, 1e30f);
    ASSERT_TRUE(hit) << i;
    EXPECT_NEAR(hit->t, 3, 0.05);
    EXPECT_FALSE(bvh->Intersect(origin, -out, 2.5f));
    const std::uint32_t* tri = &sphere.indices[3 * hit->triangle];
    const glm::vec2 b = hit->barycentrics;
    const glm::vec3 p =
        (1 - b.x - b.y) * sphere.positions[tri[0]] + b.x * sphere.positions[tri[1]] + b.y * sphere.positions[tri[2]];
    EXPECT_LE(glm::length(p - (origin - hit->t * out)), 1e-5f);
    EXPECT_GE(b.x, 0);
    EXPECT_GE(b.y, 0);
    EXPECT_LE(b.x + b.y, 1);
  }
  EXPECT_FALSE(bvh->Intersect({0, 0, 5}, {0, 0, 0}, 1e30f));  // no direction
  EXPECT_FALSE(bvh->Intersect({0, 0, 5}, {0, 0, std::numeric_limits<float>::quiet_NaN()}, 1e30f));
  // Axis-aligned rays (zero direction components) through the middle hit.
  EXPECT_TRUE(bvh->Intersect({0, 0.01f, 5}, {0, 0, -1}, 1e30f));
  EXPECT_TRUE(bvh->Intersect({0.01f, 5, 0.01f}, {0, -1, 0}, 1e30f));
}

TEST(TriangleBvh, ZeroAreaTrianglesNeverHit) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 0, 0}, {1, 1, 0}};
  m.indices = {0, 1, 2, 3, 3, 4, 0, 0, 0, 0, 3, 1};
  Result<TriangleBvh> bvh = TriangleBvh::Build(m.positions, m.indices);
  ASSERT_TRUE(bvh.ok()) << bvh.error();
  EXPECT_TRUE(bvh->nodes().empty());
  EXPECT_EQ(bvh->zero_area_triangles(), 4u);
  for (const glm::vec3 target : {glm::vec3(0.5f, 0, 0), glm::vec3(0.5f, 0.5f, 0), glm::vec3(0, 0, 0)})
    for (const glm::vec3 origin : {glm::vec3(0.3f, 0.2f, 1), glm::vec3(0.5f, 0, 1), glm::vec3(-1, 0, 0)}) {
      EXPECT_FALSE(bvh->Intersect(origin, target - origin, 1e30f));
      EXPECT_FALSE(IntersectBruteForce(m.positions, m.indices, origin, target - origin, 1e30f));
    }
}

// Two triangles sharing an edge, rays through points of the edge (and the
// shared corners): each hits at least one, as Woop et al.'s test promises.
TEST(TriangleBvh, WatertightOnASharedEdge) {
  const glm::vec3 a(0, 0, 0), b(1, 0.3f, 0.1f), c(0.2f, 1, -0.2f), d(1.3f, 1.1f, 0.4f);
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(0, 1);
  for (int i = 0; i < 20000; ++i) {
    const float s = unit(random);
    const glm::vec3 on_edge = i == 0 ? b : i == 1 ? c : b + s * (c - b);
    const glm::vec3 origin = on_edge + glm::vec3(unit(random) - 0.5f, unit(random) - 0.5f, 2);
    const RayTriangleTest test(origin, on_edge - origin);
    const bool first = test.Intersect(a, b, c, 1e30f).has_value(), second = test.Intersect(b, d, c, 1e30f).has_value();
    ASSERT_TRUE(first || second) << "s = " << s;
  }
}

TEST(TriangleBvh, BuildErrors) {
  const std::vector<glm::vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<std::uint32_t> out_of_range = {0, 1, 3};
  Result<TriangleBvh> bad = TriangleBvh::Build(p, out_of_range);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("index 2 is 3, out of range for 3 vertices"), std::string::npos) << bad.error();
  std::vector<glm::vec3> nan = p;
  nan[1].x = std::numeric_limits<float>::infinity();
  bad = TriangleBvh::Build(nan, std::vector<std::uint32_t>{0, 1, 2});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("vertex 1 has a non-finite position"), std::string::npos) << bad.error();
  bad = TriangleBvh::Build(p, std::vector<std::uint32_t>{0, 1});
  ASSERT_FALSE(bad.ok());
  bad = TriangleBvh::Build(p, std::vector<std::uint32_t>{0, 1, 2}, BvhBuildOptions{1, 4});
  ASSERT_FALSE(bad.ok());
}

// Many triangles with one centroid: no SAH split separates them, so the
// build falls back to median splits and still makes leaves of at most 4.
TEST(TriangleBvh, EqualCentroidsStillSplit) {
  Mesh m;
  for (int i = 0; i < 1000; ++i) {
    const float s = 1 + i * 0.001f;
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    m.positions.insert(m.positions.end(), {{-s, -s, 0}, {s, -s, 0}, {0, s, 0}});  // boxes centred on 0
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
  }
  Result<TriangleBvh> bvh = TriangleBvh::Build(m.positions, m.indices);
  ASSERT_TRUE(bvh.ok()) << bvh.error();
  CheckLayout(m, *bvh);
  EXPECT_LE(bvh->depth(), 64 + 33);
  const std::optional<RayHit> hit = bvh->Intersect({0, 0, 1}, {0, 0, -1}, 10);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->triangle, 0u);  // all at t = 1: the lowest index
}

}  // namespace
}  // namespace shimmer::scene
