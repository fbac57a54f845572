// Mesh assets (CPU only): glTF 2.0 as .gltf with an external or a data-URI
// buffer and as .glb, strides and normalised uvs, node transforms, computed
// normals and tangents against known answers, OBJ with MTL materials, the
// content hash, and every kind of bad input. Every fixture is written here.
#include <gtest/gtest.h>

#include <glm/gtc/constants.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "shimmer/renderer/mesh_loading.h"
#include "temp_dir.h"

namespace shimmer::scene {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using shimmer::testing::TempDir;

constexpr int kFloat = 5126, kUnsignedByte = 5121, kUnsignedShort = 5123, kUnsignedInt = 5125;

void WriteFile(const fs::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string Base64(std::string_view bytes) {
  static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t bits = 0;
  int n = 0;
  for (unsigned char c : bytes)
    for (bits = bits << 8 | c, n += 8; n >= 6; n -= 6) out += kDigits[(bits >> (n - 6)) & 63];
  if (n > 0) out += kDigits[(bits << (6 - n)) & 63];
  while (out.size() % 4) out += '=';
  return out;
}

struct GltfPrimitive {
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::vec4> tangents;
  std::vector<glm::vec2> uv;
  std::vector<std::uint32_t> indices;
  int index_type = kUnsignedInt;
  int mode = 4;
};

// A glTF document and its one binary buffer, written as .gltf + .bin, as
// .gltf with a data URI, or as .glb (glTF 2.0 spec, section 4).
class Gltf {
 public:
  Gltf() { doc_ = {{"asset", {{"version", "2.0"}}}}; }

  json& doc() { return doc_; }

  int View(const void* data, std::size_t bytes, std::size_t stride = 0) {
    while (bin_.size() % 4) bin_ += '\0';
    json view = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
    if (stride) view["byteStride"] = stride;
    bin_.append(static_cast<const char*>(data), bytes);
    return Append("bufferViews", view);
  }
  int Accessor(int view, int component, std::size_t count, const char* type, bool normalized = false,
               std::size_t offset = 0) {
    json a = {{"bufferView", view}, {"componentType", component}, {"count", count}, {"type", type}};
    if (normalized) a["normalized"] = true;
    if (offset) a["byteOffset"] = offset;
    return Append("accessors", a);
  }
  template <class T>
  int Array(const std::vector<T>& values, int component, const char* type) {
    return Accessor(View(values.data(), values.size() * sizeof(T)), component, values.size(), type);
  }
  json PrimitiveJson(const GltfPrimitive& p) {
    json attributes = {{"POSITION", Array(p.positions, kFloat, "VEC3")}};
    if (!p.normals.empty()) attributes["NORMAL"] = Array(p.normals, kFloat, "VEC3");
    if (!p.tangents.empty()) attributes["TANGENT"] = Array(p.tangents, kFloat, "VEC4");
    if (!p.uv.empty()) attributes["TEXCOORD_0"] = Array(p.uv, kFloat, "VEC2");
    json prim = {{"attributes", attributes}, {"mode", p.mode}};
    if (!p.indices.empty()) prim["indices"] = Indices(p.indices, p.index_type);
    return prim;
  }
  int Indices(const std::vector<std::uint32_t>& indices, int type) {
    std::string bytes;
    const std::size_t size = type == kUnsignedByte ? 1 : type == kUnsignedShort ? 2 : 4;
    for (std::uint32_t i : indices) bytes.append(reinterpret_cast<const char*>(&i), size);
    return Accessor(View(bytes.data(), bytes.size()), type, indices.size(), "SCALAR");
  }
  int Mesh(const GltfPrimitive& p) { return Append("meshes", {{"primitives", {PrimitiveJson(p)}}}); }
  int Node(json node) { return Append("nodes", node); }
  // A scene of these root nodes; Write makes one of node 0 (mesh 0) when none is given.
  void Scene(const std::vector<int>& roots) { doc_["scenes"] = {{{"nodes", roots}}}; }

  enum class Form { kExternalBin, kDataUri, kGlb };
  fs::path Write(const fs::path& dir, const std::string& stem, Form form) {
    if (!doc_.contains("nodes")) Node({{"mesh", 0}});
    if (!doc_.contains("scenes")) Scene({0});
    json doc = doc_;
    doc["buffers"] = {{{"byteLength", bin_.size()}}};
    if (form == Form::kExternalBin) WriteFile(dir / (stem + ".bin"), bin_);
    if (form != Form::kGlb)
      doc["buffers"][0]["uri"] =
          form == Form::kExternalBin ? stem + ".bin" : "data:application/octet-stream;base64," + Base64(bin_);
    const fs::path file = dir / (stem + (form == Form::kGlb ? ".glb" : ".gltf"));
    WriteFile(file, form == Form::kGlb ? Glb(doc.dump(), bin_) : doc.dump());
    return file;
  }

  static std::string Glb(std::string text, std::string bin) {
    while (text.size() % 4) text += ' ';
    while (bin.size() % 4) bin += '\0';
    auto u32 = [](std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
    const std::uint32_t length = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size());
    std::string glb = "glTF" + u32(2) + u32(length) + u32(text.size()) + "JSON" + text;
    if (!bin.empty()) glb += u32(bin.size()) + std::string("BIN\0", 4) + bin;
    return glb;
  }

 private:
  int Append(const char* key, const json& value) {
    doc_[key].push_back(value);
    return static_cast<int>(doc_[key].size()) - 1;
  }
  json doc_;
  std::string bin_;
};

// A unit quad in the xy plane facing +z, uv = (x, 1 - y): glTF's v grows down.
GltfPrimitive Quad() {
  GltfPrimitive p;
  p.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  p.normals.assign(4, {0, 0, 1});
  for (const glm::vec3& q : p.positions) p.uv.push_back({q.x, 1 - q.y});
  p.indices = {0, 1, 2, 0, 2, 3};
  return p;
}

// The quad, its primitive and then its document edited first.
fs::path QuadFile(const fs::path& dir, const std::string& stem, Gltf::Form form,
                  const std::function<void(GltfPrimitive&)>& primitive = {},
                  const std::function<void(json&)>& doc = {}) {
  Gltf gltf;
  GltfPrimitive quad = Quad();
  if (primitive) primitive(quad);
  gltf.Mesh(quad);
  if (doc) doc(gltf.doc());
  return gltf.Write(dir, stem, form);
}

bool Mentions(const std::vector<std::string>& lines, const std::string& a, const std::string& b) {
  for (const std::string& l : lines)
    if (l.find(a) != std::string::npos && l.find(b) != std::string::npos) return true;
  return false;
}

template <class T>
void ExpectError(const Result<T>& result, const fs::path& file, const std::string& problem) {
  ASSERT_FALSE(result.ok()) << "expected an error about " << problem;
  EXPECT_EQ(result.code(), ErrorCode::kBadInput);
  EXPECT_NE(result.error().find(file.string()), std::string::npos) << result.error();
  EXPECT_NE(result.error().find(problem), std::string::npos) << result.error();
}

void ExpectNear(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-6f) {
  EXPECT_LE(glm::length(a - b), tolerance)
      << "(" << a.x << ", " << a.y << ", " << a.z << ") vs (" << b.x << ", " << b.y << ", " << b.z << ")";
}

TEST(MeshLoading, ThreeFormsOfOneQuadAgree) {
  TempDir dir;
  std::vector<MeshAsset> assets;
  for (Gltf::Form form : {Gltf::Form::kExternalBin, Gltf::Form::kDataUri, Gltf::Form::kGlb}) {
    const fs::path file = QuadFile(dir.path(), "quad" + std::to_string(assets.size()), form,
                                   [](GltfPrimitive& quad) { quad.index_type = kUnsignedShort; });
    Result<MeshAsset> asset = LoadMeshAsset(file);
    ASSERT_TRUE(asset.ok()) << asset.error();
    ASSERT_EQ(asset->warnings.size(), 1u);  // the file has normals, not tangents
    EXPECT_TRUE(Mentions(asset->warnings, file.string(), "tangents computed"));
    EXPECT_EQ(asset->content_hash.size(), 16u);
    EXPECT_EQ(asset->files.size(), form == Gltf::Form::kExternalBin ? 2u : 1u);
    assets.push_back(std::move(*asset));
  }
  for (const MeshAsset& a : assets) {
    ASSERT_EQ(a.meshes.size(), 1u);
    const TriangleMesh& m = a.meshes[0];
    EXPECT_EQ(m.positions, Quad().positions);
    EXPECT_EQ(m.uv0, Quad().uv);
    EXPECT_EQ(m.indices, Quad().indices);
    EXPECT_EQ(m.tangents, std::vector<glm::vec4>(4, glm::vec4(1, 0, 0, 1)));
    EXPECT_DOUBLE_EQ(m.material.roughness, 1);  // the default material
  }
}

TEST(MeshLoading, InterleavedStrideNormalizedUvsAndByteIndices) {
  TempDir dir;
  struct Vertex {
    float position[3];
    std::uint16_t uv[2];
  };
  const std::vector<Vertex> vertices = {{{0, 0, 0}, {0, 65535}}, {{2, 0, 0}, {65535, 65535}}, {{0, 2, 0}, {0, 0}}};
  Gltf gltf;
  const int view = gltf.View(vertices.data(), vertices.size() * sizeof(Vertex), sizeof(Vertex));
  const int positions = gltf.Accessor(view, kFloat, 3, "VEC3");
  const int uvs = gltf.Accessor(view, kUnsignedShort, 3, "VEC2", true, offsetof(Vertex, uv));
  const int indices = gltf.Indices({0, 1, 2}, kUnsignedByte);
  gltf.doc()["meshes"] = {
      {{"primitives", {{{"attributes", {{"POSITION", positions}, {"TEXCOORD_0", uvs}}}, {"indices", indices}}}}}};
  Result<MeshAsset> asset = LoadMeshAsset(gltf.Write(dir.path(), "strided", Gltf::Form::kExternalBin));
  ASSERT_TRUE(asset.ok()) << asset.error();
  const TriangleMesh& m = asset->meshes[0];
  EXPECT_EQ(m.positions, (std::vector<glm::vec3>{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}));
  EXPECT_EQ(m.uv0, (std::vector<glm::vec2>{{0, 1}, {1, 1}, {0, 0}}));
  EXPECT_EQ(m.indices, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_TRUE(Mentions(asset->warnings, asset->file.string(), "normals computed"));
  EXPECT_TRUE(Mentions(asset->warnings, asset->file.string(), "tangents computed"));
}

// A UV sphere without normals, as a file without them would have it
// (shared vertices, the seam wrapped, one vertex per pole): the worst angle
// between computed and analytic normals, normalize(p).
double WorstSphereNormalError(const fs::path& dir, int rings, int segments) {
  GltfPrimitive p;
  p.positions.push_back({0, 1, 0});
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double theta = glm::pi<double>() * r / rings, phi = 2 * glm::pi<double>() * s / segments;
      p.positions.push_back(
          glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi)));
    }
  p.positions.push_back({0, -1, 0});
  auto ring = [&](int r, int s) { return static_cast<std::uint32_t>(1 + (r - 1) * segments + s % segments); };
  const auto south = static_cast<std::uint32_t>(p.positions.size() - 1);
  for (int s = 0; s < segments; ++s) {
    p.indices.insert(p.indices.end(), {0, ring(1, s), ring(1, s + 1)});
    for (int r = 1; r + 1 < rings; ++r)
      p.indices.insert(p.indices.end(), {ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s), ring(r + 1, s + 1),
                                         ring(r, s + 1)});
    p.indices.insert(p.indices.end(), {ring(rings - 1, s), south, ring(rings - 1, s + 1)});
  }
  Gltf gltf;
  gltf.Mesh(p);
  const fs::path file = gltf.Write(dir, "sphere" + std::to_string(rings), Gltf::Form::kGlb);
  Result<MeshAsset> asset = LoadMeshAsset(file);
  EXPECT_TRUE(asset.ok()) << asset.error();
  if (!asset) return 1;
  EXPECT_TRUE(Mentions(asset->warnings, file.string(), "normals computed"));
  const TriangleMesh& m = asset->meshes[0];
  double worst = 0;
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    const glm::dvec3 n(m.normals[i]), exact = glm::normalize(glm::dvec3(m.positions[i]));
    worst = std::max(worst, std::acos(std::min(1.0, glm::dot(n, exact))));
  }
  return worst;
}

// The error of a one-ring normal is second order in the facet size h (about
// h^2 / 3 here): halving h must quarter it.
TEST(MeshLoading, ComputedNormalsConvergeOnASphere) {
  TempDir dir;
  const double coarse = WorstSphereNormalError(dir.path(), 24, 48), fine = WorstSphereNormalError(dir.path(), 48, 96);
  const double h = glm::pi<double>() / 48;
  EXPECT_LT(fine, 0.5 * h * h) << "worst angle " << fine << " rad with facets of " << h << " rad";
  EXPECT_GT(coarse / fine, 3.5) << coarse << " vs " << fine;
}

// A cube with a vertex per face corner: each computed normal is its face's.
TEST(MeshLoading, ComputedNormalsOfACubeAreItsFaceNormals) {
  TempDir dir;
  GltfPrimitive p;
  for (int face = 0; face < 6; ++face) {  // -x, +x, -y, +y, -z, +z
    glm::vec3 n(0), u(0), v(0);
    n[face / 2] = u[(face / 2 + 1) % 3] = face % 2 ? 1.0f : -1.0f;
    v[(face / 2 + 2) % 3] = 1;  // u x v = n: counter-clockwise seen from outside
    const auto base = static_cast<std::uint32_t>(p.positions.size());
    for (glm::vec2 c : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)})
      p.positions.push_back(n + c.x * u + c.y * v);
    p.indices.insert(p.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  Gltf gltf;
  gltf.Mesh(p);
  Result<MeshAsset> asset = LoadMeshAsset(gltf.Write(dir.path(), "cube", Gltf::Form::kDataUri));
  ASSERT_TRUE(asset.ok()) << asset.error();
  for (std::size_t i = 0; i < 24; ++i) {
    glm::vec3 n(0);
    n[i / 8] = i % 8 < 4 ? -1.0f : 1.0f;
    ExpectNear(asset->meshes[0].normals[i], n);
  }
}

// A 4x4 grid in the xy plane facing +z with three uv mappings whose tangent
// frames are known: dP/du is the tangent, and the bitangent points up the
// image (toward -v), as MikkTSpace gives on (u, 1 - v).
TEST(MeshLoading, ComputedTangentsOnUvMappedPlanes) {
  struct Mapping {
    const char* name;
    glm::vec2 (*uv)(glm::vec2);
    glm::vec4 expected;
  };
  const float r = std::sqrt(0.5f);
  const Mapping mappings[] = {
      {"upright", [](glm::vec2 p) { return glm::vec2(p.x, 1 - p.y); }, {1, 0, 0, 1}},
      {"mirrored", [](glm::vec2 p) { return glm::vec2(1 - p.x, 1 - p.y); }, {-1, 0, 0, -1}},
      // u = x, v = 1 - x - y: P(u, v) = (u, 1 - u - v), dP/du = (1, -1, 0).
      {"sheared", [](glm::vec2 p) { return glm::vec2(p.x, 1 - p.x - p.y); }, {r, -r, 0, 1}},
  };
  TempDir dir;
  for (const Mapping& mapping : mappings) {
    GltfPrimitive p;
    constexpr int kSide = 4;
    for (int y = 0; y <= kSide; ++y)
      for (int x = 0; x <= kSide; ++x) {
        const glm::vec2 q(float(x) / kSide, float(y) / kSide);
        p.positions.push_back({q, 0});
        p.uv.push_back(mapping.uv(q));
      }
    p.normals.assign(p.positions.size(), {0, 0, 1});
    for (std::uint32_t y = 0; y < kSide; ++y)
      for (std::uint32_t x = 0; x < kSide; ++x) {
        const std::uint32_t i = y * (kSide + 1) + x;
        p.indices.insert(p.indices.end(), {i, i + 1, i + kSide + 2, i, i + kSide + 2, i + kSide + 1});
      }
    Gltf gltf;
    gltf.Mesh(p);
    const fs::path file = gltf.Write(dir.path(), mapping.name, Gltf::Form::kExternalBin);
    Result<MeshAsset> asset = LoadMeshAsset(file);
    ASSERT_TRUE(asset.ok()) << asset.error();
    EXPECT_TRUE(Mentions(asset->warnings, file.string(), "tangents computed")) << mapping.name;
    for (const glm::vec4& t : asset->meshes[0].tangents) {
      ExpectNear(glm::vec3(t), glm::vec3(mapping.expected), 1e-6f);
      EXPECT_EQ(t.w, mapping.expected.w) << mapping.name;
    }
  }
}

// Parent: translation (10, 0, 0), 90 degrees about +z, scale 2; child:
// translation (0, 1, 0). The vertex (1, 0, 0): child (1, 1, 0), scaled
// (2, 2, 0), rotated (-2, 2, 0), moved (8, 2, 0). A second root by matrix.
TEST(MeshLoading, NodeHierarchyTransformsPositionsNormalsAndTangents) {
  TempDir dir;
  Gltf gltf;
  GltfPrimitive p;
  p.positions = {{1, 0, 0}, {1, 1, 0}, {1, 0, 1}};
  p.normals.assign(3, {1, 0, 0});
  p.tangents.assign(3, {0, 1, 0, 1});
  p.uv = {{0, 0}, {1, 0}, {0, 1}};
  p.indices = {0, 1, 2};
  gltf.Mesh(p);
  const float s = std::sqrt(0.5f);
  gltf.Node({{"children", {1}}, {"translation", {10, 0, 0}}, {"rotation", {0, 0, s, s}}, {"scale", {2, 2, 2}}});
  gltf.Node({{"mesh", 0}, {"translation", {0, 1, 0}}});
  // Column-major: translation (0, 0, 5) in the last column.
  gltf.Node({{"mesh", 0}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1}}});
  gltf.Scene({0, 2});
  Result<MeshAsset> asset = LoadMeshAsset(gltf.Write(dir.path(), "nodes", Gltf::Form::kGlb));
  ASSERT_TRUE(asset.ok()) << asset.error();
  ASSERT_EQ(asset->meshes.size(), 2u);
  const TriangleMesh& child = asset->meshes[0];
  ExpectNear(child.positions[0], {8, 2, 0}, 1e-5f);
  ExpectNear(child.positions[1], {6, 2, 0}, 1e-5f);  // (1, 2, 0) -> (2, 4, 0) -> (-4, 2, 0) -> (6, 2, 0)
  ExpectNear(child.positions[2], {8, 2, 2}, 1e-5f);
  ExpectNear(child.normals[0], {0, 1, 0});
  EXPECT_EQ(child.tangents[0].w, 1);
  ExpectNear(glm::vec3(child.tangents[0]), {-1, 0, 0});
  ExpectNear(asset->meshes[1].positions[0], {1, 0, 5});
}

// A mirroring node keeps triangles facing their normals and flips w.
TEST(MeshLoading, MirroringNodeFlipsWindingAndHandedness) {
  TempDir dir;
  Gltf gltf;
  GltfPrimitive quad = Quad();
  quad.tangents.assign(4, {1, 0, 0, 1});
  gltf.Mesh(quad);
  gltf.Node({{"mesh", 0}, {"scale", {-1, 1, 1}}});
  Result<MeshAsset> asset = LoadMeshAsset(gltf.Write(dir.path(), "mirror", Gltf::Form::kExternalBin));
  ASSERT_TRUE(asset.ok()) << asset.error();
  const TriangleMesh& m = asset->meshes[0];
  for (std::size_t k = 0; k < m.indices.size(); k += 3) {
    const glm::vec3 face = glm::cross(m.positions[m.indices[k + 1]] - m.positions[m.indices[k]],
                                      m.positions[m.indices[k + 2]] - m.positions[m.indices[k]]);
    EXPECT_GT(glm::dot(face, m.normals[m.indices[k]]), 0);
  }
  EXPECT_EQ(m.tangents[0], glm::vec4(-1, 0, 0, -1));
}

TEST(MeshLoading, DefaultSceneIsChosen) {
  TempDir dir;
  Gltf gltf;
  gltf.Mesh(Quad());
  gltf.Node({{"mesh", 0}});
  gltf.Node({{"mesh", 0}, {"translation", {0, 0, 7}}});
  gltf.doc()["scenes"] = {{{"nodes", {0}}}, {{"nodes", {1}}}};
  gltf.doc()["scene"] = 1;
  Result<MeshAsset> asset = LoadMeshAsset(gltf.Write(dir.path(), "scenes", Gltf::Form::kDataUri));
  ASSERT_TRUE(asset.ok()) << asset.error();
  ASSERT_EQ(asset->meshes.size(), 1u);
  EXPECT_EQ(asset->meshes[0].positions[0], glm::vec3(0, 0, 7));
}

TEST(MeshLoading, GltfMaterialWithExternalAndEmbeddedTextures) {
  TempDir dir;
  Gltf gltf;
  GltfPrimitive quad = Quad();
  quad.normals.clear();
  gltf.Mesh(quad);
  const std::string png = "\x89PNG fake bytes";
  const int image_view = gltf.View(png.data(), png.size());
  gltf.doc()["images"] = {{{"uri", "normal%20map.png"}}, {{"bufferView", image_view}, {"mimeType", "image/png"}}};
  WriteFile(dir / "normal map.png", "not decoded");
  gltf.doc()["textures"] = {{{"source", 0}}, {{"source", 1}}};
  gltf.doc()["materials"] = {
      {{"name", "steel"},
       {"pbrMetallicRoughness",
        {{"roughnessFactor", 0.25}, {"metallicFactor", 0.5}, {"metallicRoughnessTexture", {{"index", 1}}}}},
       {"normalTexture", {{"index", 0}, {"scale", 0.75}}}}};
  gltf.doc()["meshes"][0]["primitives"][0]["material"] = 0;
  const fs::path file = gltf.Write(dir.path(), "material", Gltf::Form::kGlb);
  Result<MeshAsset> asset = LoadMeshAsset(file);
  ASSERT_TRUE(asset.ok()) << asset.error();
  const MeshMaterial& m = asset->meshes[0].material;
  EXPECT_EQ(m.name, "steel");
  EXPECT_DOUBLE_EQ(m.roughness, 0.25);
  EXPECT_DOUBLE_EQ(m.alpha(), 0.0625);
  EXPECT_DOUBLE_EQ(m.metallic, 0.5);
  EXPECT_EQ(m.normal_texture.file, dir / "normal map.png");
  EXPECT_DOUBLE_EQ(m.normal_scale, 0.75);
  ASSERT_NE(m.metallic_roughness_texture.encoded, nullptr);
  EXPECT_EQ(std::string(m.metallic_roughness_texture.encoded->begin(), m.metallic_roughness_texture.encoded->end()),
            png);
  EXPECT_EQ(m.metallic_roughness_texture.mime_type, "image/png");
  EXPECT_EQ(asset->files, (std::vector<fs::path>{file, dir / "normal map.png"}));
  EXPECT_TRUE(Mentions(asset->warnings, file.string(), "normals computed"));
}

TEST(MeshLoading, ObjWithTwoMaterials) {
  TempDir dir;
  WriteFile(dir / "scene.obj",
            "mtllib scene.mtl\n"
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 3 1 0\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
            "vn 0 0 1\n"
            "usemtl glossy\nf 1/1/1 2/2/1 3/3/1 4/4/1\n"
            "usemtl rough\nf 5/1/1 6/2/1 7/3/1\n");
  WriteFile(dir / "scene.mtl",
            "newmtl glossy\nKd 0.5 0.25 0.125\nPr 0.3\nPm 1\nnorm -bm 0.5 textures\\nrm.png\nmap_Pr rough.png\n"
            "newmtl rough\nNs 98\nmap_Bump bump.png\n");
  fs::create_directories(dir / "textures");
  for (const char* name : {"textures/nrm.png", "rough.png", "bump.png"}) WriteFile(dir / name, name);
  Result<MeshAsset> asset = LoadMeshAsset(dir / "scene.obj");
  ASSERT_TRUE(asset.ok()) << asset.error();
  ASSERT_EQ(asset->meshes.size(), 2u);
  const TriangleMesh& glossy = asset->meshes[0];
  EXPECT_EQ(glossy.material.name, "glossy");
  EXPECT_EQ(glossy.triangle_count(), 2u);  // the quad as a fan
  EXPECT_EQ(glossy.positions.size(), 4u);
  EXPECT_EQ(glossy.uv0[2], glm::vec2(1, 0));          // OBJ's (1, 1) with v flipped
  EXPECT_NEAR(glossy.material.roughness, 0.3, 1e-7);  // tinyobjloader reads floats
  EXPECT_DOUBLE_EQ(glossy.material.metallic, 1);
  EXPECT_EQ(glossy.material.base_color, glm::dvec4(0.5, 0.25, 0.125, 1));
  EXPECT_EQ(glossy.material.normal_texture.file, dir / "textures/nrm.png");
  EXPECT_DOUBLE_EQ(glossy.material.normal_scale, 0.5);
  EXPECT_EQ(glossy.material.metallic_roughness_texture.file, dir / "rough.png");
  ExpectNear(glm::vec3(glossy.tangents[0]), {1, 0, 0});
  EXPECT_EQ(glossy.tangents[0].w, 1);
  const TriangleMesh& rough = asset->meshes[1];
  EXPECT_EQ(rough.material.name, "rough");
  EXPECT_NEAR(rough.material.roughness, std::sqrt(std::sqrt(2.0 / 100)), 1e-6);  // Ns 98: alpha = sqrt(2 / 100)
  EXPECT_DOUBLE_EQ(rough.material.metallic, 0);
  EXPECT_EQ(rough.material.normal_texture.file, dir / "bump.png");
  EXPECT_EQ(rough.positions[0], glm::vec3(2, 0, 0));
  Result<std::vector<fs::path>> files = AssetFiles(dir / "scene.obj");
  ASSERT_TRUE(files.ok()) << files.error();
  EXPECT_EQ(*files, asset->files);
  EXPECT_EQ(files->size(), 5u);
}

TEST(MeshLoading, ContentHashFollowsContentNotPlace) {
  TempDir a, b;
  const fs::path fa = QuadFile(a.path(), "quad", Gltf::Form::kExternalBin);
  const fs::path fb = QuadFile(b.path(), "quad", Gltf::Form::kExternalBin);
  Result<std::string> ha = AssetContentHash(fa), hb = AssetContentHash(fb);
  ASSERT_TRUE(ha.ok() && hb.ok());
  EXPECT_EQ(*ha, *hb);
  EXPECT_EQ(*ha, LoadMeshAsset(fa)->content_hash);
  WriteFile(b / "quad.bin", std::string(fs::file_size(b / "quad.bin"), '\0'));  // other vertices
  Result<std::string> changed = AssetContentHash(fb);
  ASSERT_TRUE(changed.ok());
  EXPECT_NE(*ha, *changed);
}

// ---- Bad input: one error naming the file and the problem ----

TEST(MeshLoadingErrors, MalformedJsonAndUnknownExtension) {
  TempDir dir;
  WriteFile(dir / "bad.gltf", R"({"asset": {"version": "2.0"}, "meshes": [)");
  ExpectError(LoadMeshAsset(dir / "bad.gltf"), dir / "bad.gltf", "malformed JSON");
  WriteFile(dir / "model.fbx", "whatever");
  ExpectError(LoadMeshAsset(dir / "model.fbx"), dir / "model.fbx", "unknown mesh file extension '.fbx'");
  ExpectError(AssetFiles(dir / "model.fbx"), dir / "model.fbx", "unknown mesh file extension '.fbx'");
}

TEST(MeshLoadingErrors, TruncatedGlb) {
  TempDir dir;
  const fs::path file = QuadFile(dir.path(), "whole", Gltf::Form::kGlb);
  const std::string bytes = ReadAssetFile(file, 1 << 20).value();
  for (std::size_t keep : {bytes.size() - 10, std::size_t{40}, std::size_t{8}}) {
    WriteFile(dir / "cut.glb", bytes.substr(0, keep));
    ExpectError(LoadMeshAsset(dir / "cut.glb"), dir / "cut.glb", "truncated GLB");
  }
}

TEST(MeshLoadingErrors, MissingBinAndMissingImage) {
  TempDir dir;
  const fs::path file = QuadFile(dir.path(), "lost", Gltf::Form::kExternalBin);
  fs::remove(dir / "lost.bin");
  ExpectError(LoadMeshAsset(file), file, "buffer 0's file " + (dir / "lost.bin").string() + " is missing");
  const fs::path second = QuadFile(dir.path(), "image", Gltf::Form::kDataUri, {}, [](json& doc) {
    doc["images"] = {{{"uri", "gone.png"}}};
  });
  ExpectError(LoadMeshAsset(second), second, "image 0's file " + (dir / "gone.png").string() + " is missing");
}

TEST(MeshLoadingErrors, IndexOutOfRange) {
  TempDir dir;
  const fs::path file =
      QuadFile(dir.path(), "index", Gltf::Form::kDataUri, [](GltfPrimitive& quad) { quad.indices[4] = 9; });
  ExpectError(LoadMeshAsset(file), file, "index 4 (triangle 1) is 9, out of range for 4 vertices");
}

TEST(MeshLoadingErrors, NanVertex) {
  TempDir dir;
  const fs::path file = QuadFile(dir.path(), "nan", Gltf::Form::kGlb, [](GltfPrimitive& quad) {
    quad.positions[2].y = std::numeric_limits<float>::quiet_NaN();
  });
  ExpectError(LoadMeshAsset(file), file, "vertex 2 has a non-finite position");
}

TEST(MeshLoadingErrors, NoTriangles) {
  TempDir dir;
  const fs::path file = QuadFile(dir.path(), "empty", Gltf::Form::kDataUri, {}, [](json& doc) {
    doc["accessors"][doc["meshes"][0]["primitives"][0]["indices"].get<int>()]["count"] = 0;
  });
  ExpectError(LoadMeshAsset(file), file, "no triangles");
  const fs::path second = QuadFile(dir.path(), "nomesh", Gltf::Form::kDataUri, {}, [](json& doc) {
    doc["nodes"] = {{{"name", "lonely"}}};
  });  // no node has the mesh
  ExpectError(LoadMeshAsset(second), second, "no triangles");
  WriteFile(dir / "empty.obj", "v 0 0 0\nv 1 0 0\n");
  ExpectError(LoadMeshAsset(dir / "empty.obj"), dir / "empty.obj", "no triangles");
}

TEST(MeshLoadingErrors, UnsupportedRequiredExtension) {
  TempDir dir;
  const fs::path file = QuadFile(dir.path(), "draco", Gltf::Form::kGlb, {}, [](json& doc) {
    doc["extensionsRequired"] = doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  });
  ExpectError(LoadMeshAsset(file), file, "unsupported required extension KHR_draco_mesh_compression");
}

TEST(MeshLoadingErrors, OverTheMemoryLimit) {
  TempDir dir;
  const fs::path file = QuadFile(dir.path(), "big", Gltf::Form::kExternalBin);
  const std::uint64_t json_bytes = fs::file_size(file);
  ExpectError(LoadMeshAsset(file, LoadOptions{json_bytes + 8}), file, "over the limit of");
  ExpectError(LoadMeshAsset(file, LoadOptions{json_bytes - 1}), file, "over the limit of");
  WriteFile(dir / "big.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  ExpectError(LoadMeshAsset(dir / "big.obj", LoadOptions{10}), dir / "big.obj", "over the limit of");
}

TEST(MeshLoadingErrors, NonTriangleModeAndOverrunningAccessor) {
  TempDir dir;
  const fs::path file = QuadFile(dir.path(), "strip", Gltf::Form::kDataUri, [](GltfPrimitive& quad) { quad.mode = 5; });
  ExpectError(LoadMeshAsset(file), file, "primitive 0 (node 0): mode 5 (TRIANGLE_STRIP)");
  const fs::path second = QuadFile(dir.path(), "overrun", Gltf::Form::kExternalBin, {},
                                   [](json& doc) { doc["accessors"][0]["count"] = 40; });
  ExpectError(LoadMeshAsset(second), second, "POSITION (accessor 0): 40 elements");
}

TEST(MeshLoadingErrors, ObjMissingMtlAndBadFaceIndex) {
  TempDir dir;
  WriteFile(dir / "a.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  ExpectError(LoadMeshAsset(dir / "a.obj"), dir / "a.obj", (dir / "gone.mtl").string() + " (mtllib) is missing");
  WriteFile(dir / "b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n");
  ExpectError(LoadMeshAsset(dir / "b.obj"), dir / "b.obj", "face 2 refers to vertex 7, out of range for the 3");
}

}  // namespace
}  // namespace shimmer::scene
