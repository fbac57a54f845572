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

// The square [-1, 1]^2 at y = 0 facing +y, u = (x + 1) / 2, with an MTL
// roughness texture (map_Pr, 8 x 8 grey): G = 64 on its four left columns
// and 192 on its four right ones, so (G / mean G)^2 is 0.25 for u < 1/2 and
// 2.25 above; and a scene file `quad.json` that places it under a light
// from above, seen from 60 degrees up. `textured` false leaves map_Pr out.
inline std::filesystem::path WriteRoughnessQuad(const std::filesystem::path& dir, bool textured = true) {
  std::ofstream(dir / "quad.obj") << "mtllib quad.mtl\nv -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\nusemtl m\n"
                                     "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";
  std::ofstream(dir / "quad.mtl") << "newmtl m\nPr 0.5\nKd 0.5 0.5 0.5\n" << (textured ? "map_Pr rough.pgm\n" : "");
  // A binary PGM: 8 x 8 texels, one byte each.
  std::ofstream pgm(dir / "rough.pgm", std::ios::binary);
  pgm << "P5\n8 8\n255\n";
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) pgm.put(static_cast<char>(x < 4 ? 64 : 192));
  pgm.close();
  const std::filesystem::path file = dir / "quad.json";
  std::ofstream(file) << R"({"name": "roughness-quad", "assets": [{"file": "quad.obj"}],
  "light": {"type": "directional", "direction": [0, 1, 0.3]},
  "camera": {"distance": 3, "elevation_deg": 60, "fov_y_deg": 40}})";
  return file;
}

}  // namespace shimmer::testing
