// The triangle BVH on the CPU: build throughput in triangles per second on a
// random soup of 1M triangles and a tessellated sphere of 100k, and the cost
// of one closest-hit ray through each (one thread).
//   build/bench/triangle_bvh_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <glm/gtc/constants.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "shimmer/renderer/triangle_bvh.h"

namespace {

using namespace shimmer::scene;

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
};

// Triangles up to 0.02 across, uniformly in [-1, 1]^3: many overlapping boxes.
const Mesh& Soup() {
  static const Mesh mesh = [] {
    Mesh m;
    std::mt19937 random(1);
    std::uniform_real_distribution<float> unit(-1, 1);
    for (std::uint32_t i = 0; i < 1000000; ++i) {
      const glm::vec3 a(unit(random), unit(random), unit(random));
      for (int c = 0; c < 3; ++c)
        m.positions.push_back(a + 0.01f * glm::vec3(unit(random), unit(random), unit(random)));
      m.indices.insert(m.indices.end(), {3 * i, 3 * i + 1, 3 * i + 2});
    }
    return m;
  }();
  return mesh;
}

// A unit UV sphere of 2 * 224 * 223 = 99,904 triangles, shared vertices.
const Mesh& Sphere() {
  static const Mesh mesh = [] {
    constexpr int kRings = 224, kSegments = 224;
    Mesh m;
    for (int r = 0; r <= kRings; ++r)
      for (int s = 0; s < kSegments; ++s) {
        const double theta = glm::pi<double>() * r / kRings, phi = 2 * glm::pi<double>() * s / kSegments;
        m.positions.push_back(
            glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)));
      }
    auto at = [](int r, int s) { return static_cast<std::uint32_t>(r * kSegments + s % kSegments); };
    for (int r = 0; r < kRings; ++r)
      for (int s = 0; s < kSegments; ++s) {
        if (r > 0) m.indices.insert(m.indices.end(), {at(r, s), at(r, s + 1), at(r + 1, s + 1)});
        if (r + 1 < kRings) m.indices.insert(m.indices.end(), {at(r, s), at(r + 1, s + 1), at(r + 1, s)});
      }
    return m;
  }();
  return mesh;
}

void BM_Build(benchmark::State& state, const Mesh& (*mesh)()) {
  const Mesh& m = mesh();
  const double triangles = static_cast<double>(m.indices.size() / 3);
  shimmer::Result<TriangleBvh> bvh = shimmer::Result<TriangleBvh>::Failure("not built");
  for (auto _ : state) {
    bvh = TriangleBvh::Build(m.positions, m.indices);
    benchmark::DoNotOptimize(bvh);
  }
  if (!bvh) {
    state.SkipWithError(bvh.error().c_str());
    return;
  }
  state.counters["triangles"] = triangles;
  state.counters["triangles/s"] = benchmark::Counter(triangles, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["nodes"] = static_cast<double>(bvh->nodes().size());
  state.counters["depth"] = bvh->depth();
  state.counters["sah_cost"] = bvh->SahCost();
}

// Rays from a sphere of radius 3 toward random points in [-1, 1]^3: most
// hit, and each traverses to its nearest hit.
void BM_Ray(benchmark::State& state, const Mesh& (*mesh)()) {
  const Mesh& m = mesh();
  shimmer::Result<TriangleBvh> bvh = TriangleBvh::Build(m.positions, m.indices);
  if (!bvh) {
    state.SkipWithError(bvh.error().c_str());
    return;
  }
  std::mt19937 random(2);
  std::normal_distribution<float> normal;
  std::uniform_real_distribution<float> unit(-1, 1);
  std::vector<std::pair<glm::vec3, glm::vec3>> rays(1 << 16);
  for (auto& [origin, direction] : rays) {
    origin = 3.0f * glm::normalize(glm::vec3(normal(random), normal(random), normal(random)));
    direction = glm::vec3(unit(random), unit(random), unit(random)) - origin;
  }
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    const auto& [origin, direction] = rays[i++ & (rays.size() - 1)];
    const std::optional<RayHit> hit = bvh->Intersect(origin, direction, 1e30f);
    hits += hit.has_value();
    benchmark::DoNotOptimize(hit);
  }
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["hit_fraction"] = static_cast<double>(hits) / static_cast<double>(state.iterations());
}

BENCHMARK_CAPTURE(BM_Build, soup_1M, Soup)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Build, sphere_100k, Sphere)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Ray, soup_1M, Soup)->Unit(benchmark::kNanosecond);
BENCHMARK_CAPTURE(BM_Ray, sphere_100k, Sphere)->Unit(benchmark::kNanosecond);

}  // namespace

BENCHMARK_MAIN();
