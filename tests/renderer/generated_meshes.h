// Meshes the renderer tests make themselves (no third-party files): a
// subdivided icosahedron projected onto a sphere, written as OBJ with the
// sphere's exact normals, and a scene file that places it.
#pragma once

#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace shimmer::testing {

struct GeneratedMesh {
  std::vector<glm::dvec3> positions;  // on the unit sphere
  std::vector<std::uint32_t> indices;  // counter-clockwise seen from outside
};

// The icosahedron with every triangle split into four `levels` times:
// 20 * 4^levels triangles.
inline GeneratedMesh Icosphere(int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  GeneratedMesh m;
  for (glm::dvec3 p : {glm::dvec3(-1, t, 0), glm::dvec3(1, t, 0), glm::dvec3(-1, -t, 0), glm::dvec3(1, -t, 0),
                       glm::dvec3(0, -1, t), glm::dvec3(0, 1, t), glm::dvec3(0, -1, -t), glm::dvec3(0, 1, -t),
                       glm::dvec3(t, 0, -1), glm::dvec3(t, 0, 1), glm::dvec3(-t, 0, -1), glm::dvec3(-t, 0, 1)})
    m.positions.push_back(glm::normalize(p));
  m.indices = {0, 11, 5, 0, 5,  1,  0,  1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6, 7, 1, 8,
               3, 9,  4, 3, 4,  2,  3,  2, 6, 3, 6,  8,  3, 8,  9,  4, 9, 5, 2, 4,  11, 6,  2,  10, 8,  6, 7, 9, 8, 1};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      if (auto it = middle.find(key); it != middle.end()) return it->second;
      m.positions.push_back(glm::normalize(m.positions[a] + m.positions[b]));
      return middle[key] = static_cast<std::uint32_t>(m.positions.size() - 1);
    };
    std::vector<std::uint32_t> next;
    for (std::size_t k = 0; k < m.indices.size(); k += 3) {
      const std::uint32_t a = m.indices[k], b = m.indices[k + 1], c = m.indices[k + 2];
      const std::uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.indices = std::move(next);
  }
  return m;
}

// The sphere of centre `c` and radius `r` as OBJ, each vertex's normal the
// sphere's (so interpolated normals are seen against true curvature).
inline void WriteSphereObj(const std::filesystem::path& file, int levels, glm::dvec3 c, double r) {
  const GeneratedMesh m = Icosphere(levels);
  std::ofstream out(file);
  out.precision(17);
  for (const glm::dvec3& p : m.positions) out << "v " << c.x + r * p.x << " " << c.y + r * p.y << " " << c.z + r * p.z << "\n";
  for (const glm::dvec3& p : m.positions) out << "vn " << p.x << " " << p.y << " " << p.z << "\n";
  for (std::size_t k = 0; k < m.indices.size(); k += 3)
    out << "f " << m.indices[k] + 1 << "//" << m.indices[k] + 1 << " " << m.indices[k + 1] + 1 << "//"
        << m.indices[k + 1] + 1 << " " << m.indices[k + 2] + 1 << "//" << m.indices[k + 2] + 1 << "\n";
}

// A scene file in `dir` placing `asset` (a name in `dir`) with the JSON
// `transform`, above a ground plane at y = -1, lit from above and the side,
// seen from distance 4.
inline std::filesystem::path WriteMeshScene(const std::filesystem::path& dir, const std::string& asset,
                                            const std::string& transform = "{}") {
  const std::filesystem::path file = dir / "mesh-scene.json";
  std::ofstream(file) << R"({"name": "mesh-sphere", "assets": [{"file": ")" << asset
                      << R"(", "transform": )" << transform << R"(}],
  "primitives": [{"type": "plane", "height": -1}],
  "light": {"type": "directional", "direction": [0.5, 0.8, 0.3]},
  "material": "ggx:0.08",
  "camera": {"distance": 4, "elevation_deg": 20}})";
  return file;
}

}  // namespace shimmer::testing
