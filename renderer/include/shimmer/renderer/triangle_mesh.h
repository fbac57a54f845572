// Triangle meshes as the glTF 2.0 and OBJ loaders (mesh_loading.h) return
// them: the value type, the normals and tangents computed where a file has
// none, and the checks every mesh passes before anything renders it.
//
// Conventions. Positions are in world space (the file's node transforms
// applied); a counter-clockwise triangle faces the side its normals point
// to. uv0 follows glTF: (0, 0) is the image's top-left corner and v grows
// down the image (the OBJ loader flips OBJ's v). A tangent's w = +-1 picks
// the bitangent B = w cross(N, T) (glTF 2.0 spec, "Meshes", TANGENT), which
// points up the image, toward -v: the direction of a normal texture's +Y
// ("+Y is up", glTF 2.0 spec, "Materials", normalTexture).
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "shimmer/core/result.h"

namespace shimmer::scene {

// An image a material uses, not decoded: a later step sends it through the
// normal-map pipeline (normal_map.h). An external image is a file; an
// embedded one (a data URI or a GLB buffer view) keeps the bytes the asset
// stores, PNG or JPEG as they are, shared by every mesh that uses it.
struct MeshTexture {
  std::filesystem::path file;                                // resolved against the asset's directory
  std::shared_ptr<const std::vector<std::uint8_t>> encoded;  // embedded image bytes; null for a file
  std::string mime_type;                                     // "image/png", ... where the asset says
  int image = -1;                                            // the glTF image index; -1 for OBJ

  bool present() const { return !file.empty() || encoded != nullptr; }
};

struct MeshMaterial {
  std::string name;
  // glTF's perceptual roughness in [0, 1]: the GGX alpha is roughness^2
  // (glTF 2.0 spec, Appendix B "BRDF Implementation"), see alpha().
  double roughness = 1;
  double metallic = 1;       // glTF's default; OBJ materials default to 0
  glm::dvec4 base_color{1};  // linear RGBA factor
  MeshTexture normal_texture;
  double normal_scale = 1;  // glTF normalTexture.scale, OBJ "-bm": scales the texel's x and y
  // glTF: roughness in G and metallic in B, multiplying the factors. OBJ
  // map_Pr: roughness in the image's one channel.
  MeshTexture metallic_roughness_texture;

  double alpha() const { return roughness * roughness; }
};

struct TriangleMesh {
  std::string name;                  // where it came from, for messages: "mesh 0 'Hull' primitive 1"
  std::vector<glm::vec3> positions;  // world space
  std::vector<glm::vec3> normals;    // unit, one per position
  std::vector<glm::vec4>
      tangents;                // unit xyz and w = +-1, one per position; empty when neither the file nor uv0 gives them
  std::vector<glm::vec2> uv0;  // one per position, or empty
  std::vector<std::uint32_t> indices;  // three per triangle
  MeshMaterial material;

  std::size_t triangle_count() const { return indices.size() / 3; }
  // Bytes of the vertex and index arrays, for LoadOptions::max_bytes.
  std::uint64_t byte_size() const;
};

struct MeshAsset {
  std::filesystem::path file;
  std::vector<TriangleMesh> meshes;  // one per glTF primitive instance, one per OBJ material
  std::vector<std::string> warnings;
  std::vector<std::filesystem::path> files;  // `file`, then each buffer, image and MTL file it reads
  std::string content_hash;                  // AssetContentHash(file)

  std::size_t triangle_count() const;
};

// True when a, b and c are collinear (the triangle has zero area). In double
// the edge differences of floats are exact, and a cross-product component
// whose two products are equal is exactly 0, so collinear points always give
// the zero vector; a triangle thinner than double's precision may too. Such
// triangles are kept in meshes but never hit (triangle_bvh.h).
bool ZeroAreaTriangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c);

// Unit vertex normals: the sum of each triangle's unit normal weighted by its
// area and by its angle at the vertex. The angle (Thuermer and Wuethrich 1998,
// "Computing vertex normals from polygonal meshes") makes the result depend
// on the surface, not on how many triangles fan around the vertex; the area
// lowers the weight of slivers, whose normals are the least reliable. A vertex
// that no triangle with area touches gets +z.
std::vector<glm::vec3> ComputeVertexNormals(std::span<const glm::vec3> positions,
                                            std::span<const std::uint32_t> indices);

// Unit tangents with handedness (see the conventions above) from positions,
// unit normals and uv0; the method and what it equals are in triangle_mesh.cpp.
std::vector<glm::vec4> ComputeVertexTangents(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                             std::span<const glm::vec2> uv0, std::span<const std::uint32_t> indices);

// Moves `mesh` by `transform`: positions by the matrix, normals by its
// inverse transpose, tangents by the matrix, both renormalised. A mirroring
// transform (negative determinant) would turn counter-clockwise triangles
// clockwise (glTF 2.0 spec, "Meshes"), so each triangle's winding is flipped
// back, and it mirrors the bitangent, so each w changes sign. False, and
// `mesh` unchanged, for a singular or non-finite transform.
bool TransformMesh(const glm::dmat4& transform, TriangleMesh& mesh);

// What every loader runs on each mesh it makes: errors for no triangles, an
// index count that is not a multiple of 3, an index out of range, a
// non-finite position, normal, tangent or uv, or arrays of different
// lengths; then it normalises the file's normals and tangents and computes
// those the file lacks (a warning each), and counts zero-area triangles and
// zero-area uv triangles (a warning each). Messages start with `where`,
// e.g. "/a/b.gltf: mesh 0 'Hull' primitive 1".
Status CompleteMesh(const std::string& where, TriangleMesh& mesh, std::vector<std::string>& warnings);

}  // namespace shimmer::scene
