// Triangle meshes: computed normals and tangents, the checks every loaded
// mesh passes, and the asset-level file handling both loaders share
// (choosing the loader, reading files under a limit, the content hash).
#include "shimmer/renderer/triangle_mesh.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <new>
#include <system_error>

#include "shimmer/core/content_hash.h"
#include "shimmer/core/number_text.h"
#include "shimmer/renderer/mesh_loading.h"

namespace shimmer::scene {

namespace {

namespace fs = std::filesystem;
using glm::dvec3;

// The angle at `at` between the edges to p and q; with a non-zero n, between
// the edges projected onto the plane normal to n (as MikkTSpace measures it).
double CornerAngle(const dvec3& at, const dvec3& p, const dvec3& q, const dvec3& n) {
  dvec3 e1 = p - at, e2 = q - at;
  e1 -= n * glm::dot(n, e1);
  e2 -= n * glm::dot(n, e2);
  const double l1 = glm::length(e1), l2 = glm::length(e2);
  if (!(l1 > 0 && l2 > 0)) return 0;
  return std::acos(std::clamp(glm::dot(e1, e2) / (l1 * l2), -1.0, 1.0));
}

// A unit vector orthogonal to the unit n (Duff et al. 2017, "Building an
// Orthonormal Basis, Revisited", JCGT 6(1)): the tangent of a vertex whose
// triangles give no uv direction.
dvec3 AnyTangent(const dvec3& n) {
  const double sign = std::copysign(1.0, n.z);
  const double a = -1 / (sign + n.z), b = n.x * n.y * a;
  return {1 + sign * n.x * n.x * a, sign * b, -sign * n.x};
}

bool Finite(const glm::vec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }
bool Finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool Finite(const glm::vec4& v) { return Finite(glm::vec3(v)) && std::isfinite(v.w); }

glm::vec4 Widen(const glm::vec2& v) { return {v, 0, 0}; }
glm::vec4 Widen(const glm::vec3& v) { return {v, 0}; }
glm::vec4 Widen(const glm::vec4& v) { return v; }

std::string VectorText(const glm::vec4& v, int n) {
  std::string text = "(";
  for (int i = 0; i < n; ++i) text += (i ? ", " : "") + NumberText(v[i]);
  return text + ")";
}

template <class V>
Status CheckFinite(const std::string& where, const std::vector<V>& values, const char* what) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!Finite(values[i]))
      return Status::Failure(where + ": vertex " + std::to_string(i) + " has a non-finite " + what + " " +
                             VectorText(Widen(values[i]), V::length()));
  return Ok();
}

// The errors of CompleteMesh: shapes of the arrays, indices, finite values.
Status CheckArrays(const std::string& where, const TriangleMesh& mesh) {
  const std::size_t n = mesh.positions.size();
  if (mesh.indices.empty()) return Status::Failure(where + ": no triangles");
  if (mesh.indices.size() % 3 != 0)
    return Status::Failure(where + ": " + std::to_string(mesh.indices.size()) +
                           " indices, not a multiple of 3 (each triangle needs three)");
  auto same_length = [&](std::size_t size, const char* what) {
    return size == 0 || size == n ? Ok()
                                  : Status::Failure(where + ": " + std::to_string(size) + " " + what + " for " +
                                                    std::to_string(n) + " positions");
  };
  for (Status s : {same_length(mesh.normals.size(), "normals"), same_length(mesh.tangents.size(), "tangents"),
                   same_length(mesh.uv0.size(), "uvs")})
    if (!s) return s;
  for (std::size_t k = 0; k < mesh.indices.size(); ++k)
    if (mesh.indices[k] >= n)
      return Status::Failure(where + ": index " + std::to_string(k) + " (triangle " + std::to_string(k / 3) + ") is " +
                             std::to_string(mesh.indices[k]) + ", out of range for " + std::to_string(n) + " vertices");
  for (Status s : {CheckFinite(where, mesh.positions, "position"), CheckFinite(where, mesh.normals, "normal"),
                   CheckFinite(where, mesh.tangents, "tangent"), CheckFinite(where, mesh.uv0, "uv")})
    if (!s) return s;
  return Ok();
}

// The file's normals normalised, zero-length ones replaced by computed ones;
// or all computed when the file has none.
void CompleteNormals(const std::string& where, TriangleMesh& mesh, std::vector<std::string>& warnings) {
  if (mesh.normals.empty()) {
    mesh.normals = ComputeVertexNormals(mesh.positions, mesh.indices);
    warnings.push_back(where + ": normals computed: the file has none (area- and angle-weighted vertex normals)");
    return;
  }
  std::vector<glm::vec3> computed;
  std::size_t replaced = 0;
  for (std::size_t i = 0; i < mesh.normals.size(); ++i) {
    const float length = glm::length(mesh.normals[i]);
    if (length > 0) {
      mesh.normals[i] /= length;
      continue;
    }
    if (computed.empty()) computed = ComputeVertexNormals(mesh.positions, mesh.indices);
    mesh.normals[i] = computed[i];
    ++replaced;
  }
  if (replaced > 0)
    warnings.push_back(where + ": normals computed: " + std::to_string(replaced) +
                       " zero-length normals in the file replaced by computed ones");
}

// The same for tangents, which need uvs to be computed.
void CompleteTangents(const std::string& where, TriangleMesh& mesh, std::vector<std::string>& warnings) {
  if (mesh.tangents.empty()) {
    if (mesh.uv0.empty()) return;
    mesh.tangents = ComputeVertexTangents(mesh.positions, mesh.normals, mesh.uv0, mesh.indices);
    warnings.push_back(where +
                       ": tangents computed: the file has none (Lengyel's triangle tangents with MikkTSpace's "
                       "corner weights)");
    return;
  }
  std::vector<glm::vec4> computed;
  for (std::size_t i = 0; i < mesh.tangents.size(); ++i) {
    glm::vec4& t = mesh.tangents[i];
    const float length = glm::length(glm::vec3(t));
    if (length > 0) {
      t = glm::vec4(glm::vec3(t) / length, t.w < 0 ? -1.0f : 1.0f);
      continue;
    }
    if (computed.empty())
      computed = mesh.uv0.empty() ? std::vector<glm::vec4>(mesh.positions.size(), glm::vec4(0))
                                  : ComputeVertexTangents(mesh.positions, mesh.normals, mesh.uv0, mesh.indices);
    t = glm::length(glm::vec3(computed[i])) > 0 ? computed[i]
                                                : glm::vec4(glm::vec3(AnyTangent(dvec3(mesh.normals[i]))), 1.0f);
  }
}

void CountZeroAreas(const std::string& where, const TriangleMesh& mesh, std::vector<std::string>& warnings) {
  std::size_t zero = 0, zero_uv = 0;
  const auto& ix = mesh.indices;
  for (std::size_t k = 0; k < ix.size(); k += 3) {
    zero += ZeroAreaTriangle(mesh.positions[ix[k]], mesh.positions[ix[k + 1]], mesh.positions[ix[k + 2]]);
    if (!mesh.uv0.empty())
      zero_uv += ZeroAreaTriangle(glm::vec3(mesh.uv0[ix[k]], 0), glm::vec3(mesh.uv0[ix[k + 1]], 0),
                                  glm::vec3(mesh.uv0[ix[k + 2]], 0));
  }
  const std::string of = " of " + std::to_string(mesh.triangle_count()) + " triangles";
  if (zero > 0)
    warnings.push_back(where + ": " + std::to_string(zero) + of + " have zero area (kept; a ray never hits them)");
  if (zero_uv > 0)
    warnings.push_back(where + ": " + std::to_string(zero_uv) + of +
                       " have zero uv area (no tangent direction; computed tangents ignore them)");
}

std::string LowerExtension(const fs::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// An unknown extension's message, shared by LoadMeshAsset and AssetFiles.
std::string UnknownExtension(const fs::path& file) {
  return file.string() + ": unknown mesh file extension '" + file.extension().string() +
         "' (expected .gltf, .glb or .obj)";
}

Result<std::string> HashFiles(const std::vector<fs::path>& files, std::uint64_t max_bytes) {
  std::string digests;
  for (const fs::path& f : files) {
    Result<std::string> bytes = ReadAssetFile(f, max_bytes);
    if (!bytes) return bytes.failure();
    digests += Fnv1a64Hex(*bytes);
  }
  return Fnv1a64Hex(digests);
}

}  // namespace

std::uint64_t TriangleMesh::byte_size() const {
  return positions.size() * sizeof(glm::vec3) + normals.size() * sizeof(glm::vec3) +
         tangents.size() * sizeof(glm::vec4) + uv0.size() * sizeof(glm::vec2) + indices.size() * sizeof(std::uint32_t);
}

std::size_t MeshAsset::triangle_count() const {
  std::size_t n = 0;
  for (const TriangleMesh& m : meshes) n += m.triangle_count();
  return n;
}

bool ZeroAreaTriangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const dvec3 n = glm::cross(dvec3(b) - dvec3(a), dvec3(c) - dvec3(a));
  return n.x == 0 && n.y == 0 && n.z == 0;
}

std::vector<glm::vec3> ComputeVertexNormals(std::span<const glm::vec3> positions,
                                            std::span<const std::uint32_t> indices) {
  std::vector<dvec3> sum(positions.size(), dvec3(0));
  for (std::size_t k = 0; k + 2 < indices.size(); k += 3) {
    const std::uint32_t i[3] = {indices[k], indices[k + 1], indices[k + 2]};
    if (i[0] >= sum.size() || i[1] >= sum.size() || i[2] >= sum.size()) continue;
    const dvec3 p[3] = {dvec3(positions[i[0]]), dvec3(positions[i[1]]), dvec3(positions[i[2]])};
    // |cross| is twice the area: the unit normal times the area, up to a
    // factor common to all triangles.
    const dvec3 area_normal = glm::cross(p[1] - p[0], p[2] - p[0]);
    if (area_normal == dvec3(0)) continue;
    for (int c = 0; c < 3; ++c) sum[i[c]] += area_normal * CornerAngle(p[c], p[(c + 1) % 3], p[(c + 2) % 3], dvec3(0));
  }
  std::vector<glm::vec3> normals(positions.size());
  for (std::size_t v = 0; v < sum.size(); ++v) {
    const double length = glm::length(sum[v]);
    normals[v] = length > 0 ? glm::vec3(sum[v] / length) : glm::vec3(0, 0, 1);
  }
  return normals;
}

// Per triangle, dP/du from Lengyel's solution of the uv gradient (Lengyel
// 2001, "Computing Tangent Space Basis Vectors for an Arbitrary Mesh"); per
// corner, that direction made orthogonal to the vertex normal (Gram-Schmidt),
// normalised and weighted by the corner's angle in the normal's plane; per
// vertex, the normalised sum. This is MikkTSpace's accumulation (Mikkelsen
// 2008, "Simulation of Wrinkled Surfaces Revisited", and its mikktspace.c),
// so on meshes without split or degenerate uv charts (where MikkTSpace would
// split a vertex, or fill in a degenerate triangle from its neighbours) the
// result equals MikkTSpace's, which the tests check on uv-mapped planes.
//
// Handedness: MikkTSpace as Blender runs it before exporting glTF works on
// v-up coordinates (u, 1 - v), where a triangle "preserves orientation" when
// its uv area is positive; the bitangent then points toward 1 - v growing,
// up the image. Here uv is v-down, so that is a negative uv area, w = +1.
// A vertex shared by both orientations takes the one of larger angle sum.
std::vector<glm::vec4> ComputeVertexTangents(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                             std::span<const glm::vec2> uv0, std::span<const std::uint32_t> indices) {
  const std::size_t n = std::min({positions.size(), normals.size(), uv0.size()});
  std::vector<dvec3> tangent_sum(n, dvec3(0));
  std::vector<double> orientation_sum(n, 0);
  for (std::size_t k = 0; k + 2 < indices.size(); k += 3) {
    const std::uint32_t i[3] = {indices[k], indices[k + 1], indices[k + 2]};
    if (i[0] >= n || i[1] >= n || i[2] >= n) continue;
    const dvec3 p[3] = {dvec3(positions[i[0]]), dvec3(positions[i[1]]), dvec3(positions[i[2]])};
    if (ZeroAreaTriangle(positions[i[0]], positions[i[1]], positions[i[2]])) continue;
    const glm::dvec2 d1 = glm::dvec2(uv0[i[1]]) - glm::dvec2(uv0[i[0]]);
    const glm::dvec2 d2 = glm::dvec2(uv0[i[2]]) - glm::dvec2(uv0[i[0]]);
    const double det = d1.x * d2.y - d2.x * d1.y;
    if (det == 0) continue;
    const dvec3 dp_du = ((p[1] - p[0]) * d2.y - (p[2] - p[0]) * d1.y) / det;
    const double w = det < 0 ? 1 : -1;
    for (int c = 0; c < 3; ++c) {
      const dvec3 normal(normals[i[c]]);
      const dvec3 t = dp_du - normal * glm::dot(normal, dp_du);
      const double length = glm::length(t);
      if (!(length > 0) || !std::isfinite(length)) continue;
      const double angle = CornerAngle(p[c], p[(c + 1) % 3], p[(c + 2) % 3], normal);
      tangent_sum[i[c]] += t / length * angle;
      orientation_sum[i[c]] += w * angle;
    }
  }
  std::vector<glm::vec4> tangents(positions.size(), glm::vec4(1, 0, 0, 1));
  for (std::size_t v = 0; v < n; ++v) {
    const dvec3 normal(normals[v]);
    dvec3 t = tangent_sum[v] - normal * glm::dot(normal, tangent_sum[v]);
    const double length = glm::length(t);
    t = length > 1e-12 ? t / length : AnyTangent(normal);
    tangents[v] = glm::vec4(glm::vec3(t), orientation_sum[v] < 0 ? -1.0f : 1.0f);
  }
  return tangents;
}

bool TransformMesh(const glm::dmat4& transform, TriangleMesh& mesh) {
  const glm::dmat3 linear(transform);
  const double det = glm::determinant(linear);
  if (!(det != 0) || !std::isfinite(det)) return false;
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
  for (glm::vec3& p : mesh.positions) p = glm::vec3(transform * glm::dvec4(p, 1));
  for (glm::vec3& n : mesh.normals) {
    const dvec3 v = normal_matrix * dvec3(n);
    n = glm::length(v) > 0 ? glm::vec3(glm::normalize(v)) : glm::vec3(0);
  }
  for (glm::vec4& t : mesh.tangents) {
    const dvec3 v = linear * dvec3(t);
    t = glm::vec4(glm::length(v) > 0 ? glm::vec3(glm::normalize(v)) : glm::vec3(0), det < 0 ? -t.w : t.w);
  }
  if (det < 0)
    for (std::size_t k = 0; k + 2 < mesh.indices.size(); k += 3) std::swap(mesh.indices[k + 1], mesh.indices[k + 2]);
  return true;
}

Status CompleteMesh(const std::string& where, TriangleMesh& mesh, std::vector<std::string>& warnings) {
  if (Status s = CheckArrays(where, mesh); !s) return s;
  CountZeroAreas(where, mesh, warnings);
  CompleteNormals(where, mesh, warnings);
  CompleteTangents(where, mesh, warnings);
  return Ok();
}

// ---- Files ----

Result<std::string> ReadAssetFile(const fs::path& file, std::uint64_t max_bytes) {
  std::error_code error;
  if (!fs::exists(file, error)) return Result<std::string>::Failure(file.string() + ": no such file");
  if (!fs::is_regular_file(file, error)) return Result<std::string>::Failure(file.string() + ": not a regular file");
  const std::uintmax_t size = fs::file_size(file, error);
  if (error) return Result<std::string>::Failure(file.string() + ": " + error.message(), ErrorCode::kIo);
  if (size > max_bytes)
    return Result<std::string>::Failure(file.string() + ": the file is " + std::to_string(size) +
                                        " bytes, over the limit of " + std::to_string(max_bytes) +
                                        " bytes (LoadOptions::max_bytes)");
  std::ifstream in(file, std::ios::binary);
  std::string bytes(size, '\0');
  if (!in || !in.read(bytes.data(), static_cast<std::streamsize>(size)))
    return Result<std::string>::Failure(file.string() + ": could not be read", ErrorCode::kIo);
  return bytes;
}

Result<MeshAsset> LoadMeshAsset(const fs::path& file, const LoadOptions& options) {
  const std::string ext = LowerExtension(file);
  if (ext != ".gltf" && ext != ".glb" && ext != ".obj") return Result<MeshAsset>::Failure(UnknownExtension(file));
  // The byte limit bounds what a file can ask for; an allocation can still
  // fail on a smaller host, and no exception may leave a loader.
  try {
    Result<MeshAsset> asset = ext == ".obj" ? LoadObjAsset(file, options) : LoadGltfAsset(file, options);
    if (!asset) return asset;
    Result<std::string> hash = HashFiles(asset->files, options.max_bytes);
    if (!hash) return hash.failure();
    asset->content_hash = *hash;
    return asset;
  } catch (const std::bad_alloc&) {
    return Result<MeshAsset>::Failure(file.string() + ": out of memory while loading", ErrorCode::kOutOfMemory);
  }
}

Result<std::vector<fs::path>> AssetFiles(const fs::path& file) {
  const std::string ext = LowerExtension(file);
  if (ext == ".gltf" || ext == ".glb") return GltfAssetFiles(file);
  if (ext == ".obj") return ObjAssetFiles(file);
  return Result<std::vector<fs::path>>::Failure(UnknownExtension(file));
}

Result<std::string> AssetContentHash(const fs::path& file, const LoadOptions& options) {
  Result<std::vector<fs::path>> files = AssetFiles(file);
  if (!files) return files.failure();
  return HashFiles(*files, options.max_bytes);
}

}  // namespace shimmer::scene
