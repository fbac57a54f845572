// OBJ assets and their MTL files through tinyobjloader (Debian's
// libtinyobjloader). The OBJ and MTL files are read here, under the byte
// limit, and handed to tinyobjloader as streams; faces come back untriangulated
// and are split into fans here, after their indices are checked (tinyobjloader
// does not check them against the vertex counts).
#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <system_error>
#include <unordered_map>

#include "shimmer/renderer/mesh_loading.h"

namespace shimmer::scene {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> Words(std::string_view line) {
  std::vector<std::string> words;
  std::istringstream in{std::string(line)};
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

// Calls `f` with the words of each line.
template <class F>
void ForEachLine(std::string_view text, F f) {
  for (std::size_t start = 0; start < text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    f(Words(text.substr(start, end - start)));
    start = end + 1;
  }
}

// Texture and MTL names as paths under `dir`; MTL files written on Windows
// separate folders with backslashes.
fs::path Resolved(const fs::path& dir, std::string name) {
  std::replace(name.begin(), name.end(), '\\', '/');
  return dir / name;
}

// What the MTL files say beyond what tinyobjloader keeps: whether Pr, Ns and
// Pm were given at all (tinyobjloader stores 0 when they are absent), and the
// directory the material's textures are relative to.
struct MtlFacts {
  fs::path dir;
  bool has_pr = false, has_ns = false, has_pm = false;
};

struct MtlFiles {
  std::vector<fs::path> files;
  std::string text;  // every file, in order
  std::map<std::string, MtlFacts> facts;
  std::uint64_t bytes = 0;
};

void ScanMtl(std::string_view text, const fs::path& dir, std::map<std::string, MtlFacts>& facts) {
  MtlFacts* current = nullptr;
  ForEachLine(text, [&](const std::vector<std::string>& w) {
    if (w.empty()) return;
    if (w[0] == "newmtl" && w.size() >= 2) {
      const bool fresh = !facts.count(w[1]);
      current = fresh ? &facts[w[1]] : nullptr;  // the first definition wins, as in tinyobjloader
      if (current) current->dir = dir;
    } else if (current) {
      current->has_pr |= w[0] == "Pr";
      current->has_ns |= w[0] == "Ns";
      current->has_pm |= w[0] == "Pm";
    }
  });
}

// The files on the OBJ's mtllib lines, read and scanned; a missing one is an
// error (tinyobjloader would only warn, and load the asset without materials).
Result<MtlFiles> ReadMtlFiles(const std::string& name, std::string_view obj, const fs::path& dir,
                              std::uint64_t max_bytes) {
  MtlFiles mtl;
  std::vector<fs::path> named;
  ForEachLine(obj, [&](const std::vector<std::string>& w) {
    if (!w.empty() && w[0] == "mtllib")
      for (std::size_t i = 1; i < w.size(); ++i) named.push_back(Resolved(dir, w[i]));
  });
  for (const fs::path& file : named) {
    if (std::find(mtl.files.begin(), mtl.files.end(), file) != mtl.files.end()) continue;
    std::error_code error;
    if (!fs::is_regular_file(file, error))
      return Result<MtlFiles>::Failure(name + ": its MTL file " + file.string() + " (mtllib) is missing");
    Result<std::string> text = ReadAssetFile(file, max_bytes);
    if (!text) return text.failure();
    mtl.bytes += text->size();
    ScanMtl(*text, file.parent_path(), mtl.facts);
    mtl.text += *text + "\n";
    mtl.files.push_back(file);
  }
  return mtl;
}

// Hands tinyobjloader every MTL file at the first mtllib line and nothing at
// later ones (its stream reader would warn that the stream is spent).
class MtlOnce : public tinyobj::MaterialReader {
 public:
  explicit MtlOnce(const std::string& text) : text_(text) {}
  bool operator()(const std::string&, std::vector<tinyobj::material_t>* materials, std::map<std::string, int>* names,
                  std::string* warning, std::string* error) override {
    if (done_) return true;
    done_ = true;
    std::istringstream in(text_);
    tinyobj::LoadMtl(names, materials, &in, warning, error);
    return true;
  }

 private:
  const std::string& text_;
  bool done_ = false;
};

// Blinn-Phong exponent to roughness: Walter et al. 2007 ("Microfacet Models
// for Refraction through Rough Surfaces", section 5.2) match a Phong
// exponent Ns to the Beckmann width alpha = sqrt(2 / (Ns + 2)); taken as
// GGX's alpha = roughness^2, roughness = sqrt(alpha).
double RoughnessFromShininess(double ns) { return std::sqrt(std::sqrt(2 / (std::max(ns, 0.0) + 2))); }

struct ObjTextures {
  std::string normal;  // norm, else map_Bump / bump
  double normal_scale = 1;
  std::string roughness;  // map_Pr
};

ObjTextures TexturesOf(const tinyobj::material_t& m) {
  ObjTextures t;
  const bool norm = !m.normal_texname.empty();
  t.normal = norm ? m.normal_texname : m.bump_texname;
  t.normal_scale = norm ? m.normal_texopt.bump_multiplier : m.bump_texopt.bump_multiplier;
  t.roughness = m.roughness_texname;
  return t;
}

Result<MeshTexture> TextureFile(const std::string& where, const fs::path& dir, const std::string& texname) {
  MeshTexture t;
  if (texname.empty()) return t;
  t.file = Resolved(dir, texname);
  std::error_code error;
  if (!fs::is_regular_file(t.file, error))
    return Result<MeshTexture>::Failure(where + ": texture file " + t.file.string() + " is missing");
  return t;
}

Result<MeshMaterial> MaterialOf(const std::vector<tinyobj::material_t>& materials, int id, const MtlFiles& mtl,
                                const std::string& name) {
  MeshMaterial m;
  m.metallic = 0;
  if (id < 0 || static_cast<std::size_t>(id) >= materials.size()) return m;
  const tinyobj::material_t& source = materials[id];
  const auto found = mtl.facts.find(source.name);
  const MtlFacts facts = found != mtl.facts.end() ? found->second : MtlFacts{};
  m.name = source.name;
  m.roughness = facts.has_pr   ? std::clamp<double>(source.roughness, 0, 1)
                : facts.has_ns ? RoughnessFromShininess(source.shininess)
                               : 1;
  m.metallic = facts.has_pm ? std::clamp<double>(source.metallic, 0, 1) : 0;
  m.base_color = {source.diffuse[0], source.diffuse[1], source.diffuse[2], source.dissolve};
  const ObjTextures textures = TexturesOf(source);
  const std::string where = name + ": material '" + source.name + "'";
  Result<MeshTexture> normal = TextureFile(where, facts.dir, textures.normal);
  if (!normal) return normal.failure();
  m.normal_texture = std::move(*normal);
  m.normal_scale = textures.normal_scale;
  Result<MeshTexture> roughness = TextureFile(where, facts.dir, textures.roughness);
  if (!roughness) return roughness.failure();
  m.metallic_roughness_texture = std::move(*roughness);
  return m;
}

// Every material of the MTL files (used or not, so that the asset's files do
// not depend on the faces), and the texture files they add to `files`.
Result<std::vector<MeshMaterial>> AllMaterials(const std::vector<tinyobj::material_t>& materials, const MtlFiles& mtl,
                                               const std::string& name, std::vector<fs::path>& files) {
  std::vector<MeshMaterial> out;
  for (std::size_t id = 0; id < materials.size(); ++id) {
    Result<MeshMaterial> material = MaterialOf(materials, static_cast<int>(id), mtl, name);
    if (!material) return material.failure();
    for (const MeshTexture* t : {&material->normal_texture, &material->metallic_roughness_texture})
      if (t->present() && std::find(files.begin(), files.end(), t->file) == files.end()) files.push_back(t->file);
    out.push_back(std::move(*material));
  }
  return out;
}

// ---- Faces ----

struct Group {
  int material = -1;
  std::vector<tinyobj::index_t> corners;  // three per triangle
};

Status CheckCorner(const std::string& name, const tinyobj::attrib_t& attrib, const tinyobj::index_t& c,
                   std::size_t face) {
  const std::size_t counts[3] = {attrib.vertices.size() / 3, attrib.texcoords.size() / 2, attrib.normals.size() / 3};
  const int indices[3] = {c.vertex_index, c.texcoord_index, c.normal_index};
  const char* kinds[3] = {"vertex", "texture coordinate", "normal"};
  for (int k = 0; k < 3; ++k)
    if ((k == 0 && indices[k] < 0) || (indices[k] >= 0 && static_cast<std::size_t>(indices[k]) >= counts[k]))
      return Status::Failure(name + ": face " + std::to_string(face + 1) + " refers to " + kinds[k] + " " +
                             std::to_string(indices[k] + 1) + ", out of range for the " + std::to_string(counts[k]) +
                             " in the file");
  return Ok();
}

// Every face split into a fan (right for the convex polygons OBJ files
// hold), grouped by material in order of first use.
Result<std::vector<Group>> Triangulate(const std::string& name, const tinyobj::attrib_t& attrib,
                                       const std::vector<tinyobj::shape_t>& shapes, std::size_t& skipped) {
  std::vector<Group> groups;
  std::size_t face_number = 0;
  for (const tinyobj::shape_t& shape : shapes) {
    std::size_t offset = 0;
    for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f, ++face_number) {
      const std::size_t n = shape.mesh.num_face_vertices[f];
      const tinyobj::index_t* corners = shape.mesh.indices.data() + offset;
      offset += n;
      for (std::size_t k = 0; k < n; ++k)
        if (Status s = CheckCorner(name, attrib, corners[k], face_number); !s) return s.failure();
      if (n < 3) {
        ++skipped;
        continue;
      }
      const int material = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
      auto group = std::find_if(groups.begin(), groups.end(), [&](const Group& g) { return g.material == material; });
      if (group == groups.end()) group = groups.insert(groups.end(), Group{material, {}});
      for (std::size_t k = 1; k + 1 < n; ++k)
        group->corners.insert(group->corners.end(), {corners[0], corners[k], corners[k + 1]});
    }
  }
  return groups;
}

struct CornerHash {
  std::size_t operator()(const std::array<int, 3>& k) const {
    return static_cast<std::size_t>(static_cast<std::uint32_t>(k[0])) * 0x9E3779B97F4A7C15ull ^
           static_cast<std::uint32_t>(k[1]) * 0xC2B2AE3D27D4EB4Full ^ static_cast<std::uint32_t>(k[2]);
  }
};

// One vertex per distinct (v, vt, vn) triple. A group in which only some
// corners have a uv (or a normal) gets none, with a warning.
TriangleMesh Deindexed(const tinyobj::attrib_t& attrib, const Group& group, const std::string& where,
                       std::vector<std::string>& warnings) {
  std::size_t with_uv = 0, with_normal = 0;
  for (const tinyobj::index_t& c : group.corners) {
    with_uv += c.texcoord_index >= 0;
    with_normal += c.normal_index >= 0;
  }
  const bool uv = with_uv == group.corners.size(), normal = with_normal == group.corners.size();
  if (!uv && with_uv > 0) warnings.push_back(where + ": only some corners have texture coordinates; all dropped");
  if (!normal && with_normal > 0) warnings.push_back(where + ": only some corners have normals; all dropped");
  TriangleMesh mesh;
  std::unordered_map<std::array<int, 3>, std::uint32_t, CornerHash> ids;
  for (const tinyobj::index_t& c : group.corners) {
    const std::array<int, 3> key = {c.vertex_index, uv ? c.texcoord_index : -1, normal ? c.normal_index : -1};
    const auto [it, fresh] = ids.try_emplace(key, static_cast<std::uint32_t>(mesh.positions.size()));
    mesh.indices.push_back(it->second);
    if (!fresh) continue;
    const float* p = &attrib.vertices[3 * static_cast<std::size_t>(c.vertex_index)];
    mesh.positions.emplace_back(p[0], p[1], p[2]);
    if (uv) {
      const float* t = &attrib.texcoords[2 * static_cast<std::size_t>(c.texcoord_index)];
      mesh.uv0.emplace_back(t[0], 1 - t[1]);  // OBJ's v grows up the image, glTF's down
    }
    if (normal) {
      const float* n = &attrib.normals[3 * static_cast<std::size_t>(c.normal_index)];
      mesh.normals.emplace_back(n[0], n[1], n[2]);
    }
  }
  return mesh;
}

}  // namespace

Result<MeshAsset> LoadObjAsset(const fs::path& file, const LoadOptions& options) {
  using R = Result<MeshAsset>;
  const std::string name = file.string();
  Result<std::string> obj = ReadAssetFile(file, options.max_bytes);
  if (!obj) return obj.failure();
  Result<MtlFiles> mtl = ReadMtlFiles(name, *obj, file.parent_path(), options.max_bytes);
  if (!mtl) return mtl.failure();
  if (obj->size() + mtl->bytes > options.max_bytes)
    return R::Failure(name + ": the OBJ and MTL files take " + std::to_string(obj->size() + mtl->bytes) +
                      " bytes, over the limit of " + std::to_string(options.max_bytes) +
                      " bytes (LoadOptions::max_bytes)");
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warning, error;
  bool ok = false;
  try {
    std::istringstream in(*obj);
    MtlOnce reader(mtl->text);
    ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warning, &error, &in, &reader, false, false);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!ok) return R::Failure(name + ": not a readable OBJ file: " + error.substr(0, error.find('\n')));
  MeshAsset asset;
  asset.file = file;
  asset.files.push_back(file);
  asset.files.insert(asset.files.end(), mtl->files.begin(), mtl->files.end());
  if (!warning.empty()) asset.warnings.push_back(name + ": " + warning.substr(0, warning.find('\n')));
  Result<std::vector<MeshMaterial>> all = AllMaterials(materials, *mtl, name, asset.files);
  if (!all) return all.failure();
  std::size_t skipped = 0;
  Result<std::vector<Group>> groups = Triangulate(name, attrib, shapes, skipped);
  if (!groups) return groups.failure();
  if (skipped > 0)
    asset.warnings.push_back(name + ": " + std::to_string(skipped) + " faces with fewer than 3 vertices left out");
  std::uint64_t bytes = 0;
  for (const Group& group : *groups) {
    const bool known = group.material >= 0 && static_cast<std::size_t>(group.material) < all->size();
    MeshMaterial material = known ? (*all)[group.material] : MaterialOf(materials, -1, *mtl, name).value();
    const std::string label = "material '" + (known ? material.name : std::string("(none)")) + "'";
    const std::string where = name + ": " + label;
    TriangleMesh mesh = Deindexed(attrib, group, where, asset.warnings);
    mesh.name = label;
    mesh.material = std::move(material);
    if (Status s = CompleteMesh(where, mesh, asset.warnings); !s) return s.failure();
    bytes += mesh.byte_size();
    if (bytes > options.max_bytes)
      return R::Failure(name + ": the meshes take over " + std::to_string(options.max_bytes) +
                        " bytes, the limit (LoadOptions::max_bytes)");
    asset.meshes.push_back(std::move(mesh));
  }
  if (asset.meshes.empty()) return R::Failure(name + ": no triangles: the file has no faces");
  return asset;
}

Result<std::vector<fs::path>> ObjAssetFiles(const fs::path& file) {
  const std::string name = file.string();
  Result<std::string> obj = ReadAssetFile(file, LoadOptions{}.max_bytes);
  if (!obj) return obj.failure();
  Result<MtlFiles> mtl = ReadMtlFiles(name, *obj, file.parent_path(), LoadOptions{}.max_bytes);
  if (!mtl) return mtl.failure();
  std::vector<fs::path> files = {file};
  files.insert(files.end(), mtl->files.begin(), mtl->files.end());
  std::map<std::string, int> names;
  std::vector<tinyobj::material_t> materials;
  std::string warning, error;
  std::istringstream in(mtl->text);
  tinyobj::LoadMtl(&names, &materials, &in, &warning, &error);
  Result<std::vector<MeshMaterial>> all = AllMaterials(materials, *mtl, name, files);
  if (!all) return all.failure();
  return files;
}

}  // namespace shimmer::scene
