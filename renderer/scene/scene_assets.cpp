// Mesh assets placed in scenes: a file loaded (mesh_loading.h), moved by its
// transform, its meshes merged into one with one BVH (triangle_bvh.h), and
// the result kept per process by the asset's path, content and transform, so
// that the jobs of a spec load and build each placement once.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "shimmer/core/content_hash.h"
#include "shimmer/renderer/mesh_loading.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::scene {

namespace {

struct PlacementCache {
  std::mutex mutex;
  std::map<std::string, std::shared_ptr<const PlacedMesh>> placed;
};
PlacementCache& Placements() {
  static auto* cache = new PlacementCache;  // leaked: scenes are loaded until exit
  return *cache;
}

std::string TransformKey(const glm::dmat4& m) {
  std::string bytes(sizeof m, '\0');
  std::memcpy(bytes.data(), &m, sizeof m);
  return Fnv1a64Hex(bytes);
}

// The meshes of `asset` in one, each moved by `transform` first (a mesh
// without uv or tangents gets zero ones: the kernel then takes its default
// tangent).
Result<TriangleMesh> Merged(const MeshAsset& asset, const glm::dmat4& transform) {
  TriangleMesh all;
  all.name = asset.file.string();
  for (TriangleMesh mesh : asset.meshes) {
    if (!TransformMesh(transform, mesh))
      return Result<TriangleMesh>::Failure(asset.file.string() + ": the transform is singular or not finite");
    const auto base = static_cast<std::uint32_t>(all.positions.size());
    const std::size_t n = mesh.positions.size();
    all.positions.insert(all.positions.end(), mesh.positions.begin(), mesh.positions.end());
    all.normals.insert(all.normals.end(), mesh.normals.begin(), mesh.normals.end());
    if (mesh.tangents.size() == n)
      all.tangents.insert(all.tangents.end(), mesh.tangents.begin(), mesh.tangents.end());
    else
      all.tangents.resize(all.tangents.size() + n, glm::vec4(0, 0, 0, 1));
    if (mesh.uv0.size() == n)
      all.uv0.insert(all.uv0.end(), mesh.uv0.begin(), mesh.uv0.end());
    else
      all.uv0.resize(all.uv0.size() + n, glm::vec2(0));
    for (std::uint32_t i : mesh.indices) all.indices.push_back(base + i);
  }
  if (!asset.meshes.empty()) all.material = asset.meshes.front().material;
  return all;
}

}  // namespace

std::size_t PackedMeshWords(const PlacedMesh& mesh) {
  return 1 + 2 * mesh.bvh.nodes().size() + 3 * mesh.bvh.triangle_order().size() + 3 * mesh.mesh.positions.size();
}

Result<std::shared_ptr<const PlacedMesh>> PlaceAsset(const std::filesystem::path& file, const glm::dmat4& transform) {
  using R = Result<std::shared_ptr<const PlacedMesh>>;
  auto hash = AssetContentHash(file);
  if (!hash) return hash.failure();
  // The path is part of the key as well as the content: a placed mesh keeps
  // the paths of its texture files, and an equal copy of the asset in another
  // folder must read its own (the first copy's may be gone).
  const std::string key = std::filesystem::absolute(file).lexically_normal().string() + ":" + *hash + ":" +
                          TransformKey(transform);
  PlacementCache& cache = Placements();
  {
    std::lock_guard lock(cache.mutex);
    if (auto it = cache.placed.find(key); it != cache.placed.end()) return it->second;
  }
  auto asset = LoadMeshAsset(file);
  if (!asset) return asset.failure();
  auto merged = Merged(*asset, transform);
  if (!merged) return merged.failure();
  auto bvh = TriangleBvh::Build(*merged);
  if (!bvh) return R::Failure(file.string() + ": " + bvh.error());
  if (bvh->nodes().empty()) return R::Failure(file.string() + ": every triangle has zero area; nothing to render");
  if (bvh->depth() + 1 >= kMaxMeshBvhDepth)
    return R::Failure(file.string() + ": its BVH is " + std::to_string(bvh->depth() + 1) + " levels deep; the kernel walks at most " +
                      std::to_string(kMaxMeshBvhDepth - 1));
  auto placed = std::make_shared<PlacedMesh>();
  placed->file = file;
  placed->content_hash = asset->content_hash;
  placed->transform = transform;
  placed->warnings = asset->warnings;
  placed->mesh = std::move(*merged);
  placed->bvh = std::move(*bvh);
  const glm::vec3 lo = placed->bvh.nodes().front().lo, hi = placed->bvh.nodes().front().hi;
  placed->lo = lo;
  placed->hi = hi;
  if (glm::length(placed->lo) > kMaxCoordinate || glm::length(placed->hi) > kMaxCoordinate)
    return R::Failure(file.string() + ": placed, its bounds reach past 1e6 from the origin");
  if (PackedMeshWords(*placed) >= kMaxSceneWords)
    return R::Failure(file.string() + ": " + std::to_string(placed->mesh.triangle_count()) + " triangles and " +
                      std::to_string(placed->mesh.positions.size()) +
                      " vertices take more than the kernel's 2^24 scene words; use a smaller asset");
  std::lock_guard lock(cache.mutex);
  return cache.placed.emplace(key, std::move(placed)).first->second;
}

namespace {

// Textures the kernel reads texel by texel are kept within this side.
constexpr int kMaxRoughnessSide = 4096;

// The roughness texture's roughness channel in [0, 1], as doubles.
Result<cv::Mat> RoughnessChannel(const MeshTexture& t) {
  cv::Mat image = t.encoded ? cv::imdecode(*t.encoded, cv::IMREAD_UNCHANGED) : cv::imread(t.file.string(), cv::IMREAD_UNCHANGED);
  const std::string name = t.encoded ? "the embedded image " + std::to_string(t.image) : t.file.string();
  if (image.empty()) return Result<cv::Mat>::Failure(name + ": the roughness texture cannot be read (PNG or JPEG expected)");
  const double full = image.depth() == CV_16U ? 65535.0 : image.depth() == CV_8U ? 255.0 : 0.0;
  if (full == 0) return Result<cv::Mat>::Failure(name + ": the roughness texture is not 8 or 16 bits per channel");
  if (image.cols > kMaxRoughnessSide || image.rows > kMaxRoughnessSide)
    return Result<cv::Mat>::Failure(name + ": the roughness texture is " + std::to_string(image.cols) + "x" +
                                    std::to_string(image.rows) + "; at most " + std::to_string(kMaxRoughnessSide) +
                                    " texels a side are read");
  // OpenCV orders colour channels B, G, R(, A): glTF's G is channel 1; a grey image has one.
  cv::Mat g;
  cv::extractChannel(image, g, image.channels() >= 3 ? 1 : 0);
  g.convertTo(g, CV_64F, 1.0 / full);
  return g;
}

}  // namespace

std::size_t PackedRoughnessWords(const RoughnessMap& map) {
  return 1 + (map.alpha_factor.size() + 3) / 4;
}

Result<std::shared_ptr<const RoughnessMap>> RoughnessMapOfMesh(const MeshMaterial& m) {
  const MeshTexture& t = m.metallic_roughness_texture;
  if (!t.present()) return std::shared_ptr<const RoughnessMap>();
  auto g = RoughnessChannel(t);
  if (!g) return g.failure();
  double lo = 0, hi = 0;
  cv::minMaxLoc(*g, &lo, &hi);
  const double mean = cv::mean(*g)[0];
  // Uniform: the material's alpha is the whole story. All black: alpha is
  // clamped to its floor everywhere (MaterialOfMesh), a ratio has no meaning.
  if (lo == hi || mean <= 0) return std::shared_ptr<const RoughnessMap>();
  auto map = std::make_shared<RoughnessMap>();
  map->width = g->cols;
  map->height = g->rows;
  map->alpha_factor.reserve(std::size_t(g->total()));
  for (int y = 0; y < g->rows; ++y)
    for (int x = 0; x < g->cols; ++x) {
      const double r = g->at<double>(y, x) / mean;
      map->alpha_factor.push_back(static_cast<float>(r * r));
    }
  return std::shared_ptr<const RoughnessMap>(std::move(map));
}

Result<shading::MaterialDesc> MaterialOfMesh(const MeshMaterial& m) {
  double roughness = m.roughness;
  if (const MeshTexture& t = m.metallic_roughness_texture; t.present()) {
    auto g = RoughnessChannel(t);
    if (!g) return g.failure();
    roughness *= cv::mean(*g)[0];
  }
  shading::MaterialDesc d;
  d.ndf = shading::Ndf::kGgx;
  const double alpha = std::clamp(roughness * roughness, 1e-4, 1.0);
  d.alpha = {alpha, alpha};
  const glm::dvec3 base(m.base_color);
  d.f0 = glm::mix(glm::dvec3(0.04), base, m.metallic);
  d.albedo = base * (1 - m.metallic);
  return d;
}

Result<std::shared_ptr<const NormalMap>> NormalMapOfMesh(const MeshMaterial& m, NormalMapSource* source) {
  using R = Result<std::shared_ptr<const NormalMap>>;
  const MeshTexture& t = m.normal_texture;
  if (!t.present()) return std::shared_ptr<const NormalMap>();
  if (t.encoded)
    return R::Failure("the normal texture is embedded (image " + std::to_string(t.image) +
                      "); give the asset entry a 'normal_map' with the image as a file");
  NormalMapSource s;
  s.file = t.file.string();
  s.strength = std::clamp(m.normal_scale, 0.0, 10.0);
  auto map = LoadNormalMap(s);
  if (!map) return map.failure();
  *source = s;
  return *map;
}

CameraRig FramingRig(glm::dvec3 centre, double radius, double fov_y_deg) {
  constexpr double kPi = 3.14159265358979323846;
  CameraRig rig;
  rig.target = centre;
  rig.fov_y_deg = fov_y_deg;
  rig.elevation_deg = 20;
  rig.azimuth_deg = 30;
  rig.distance = std::max(radius, 1e-6) / (0.9 * std::sin(fov_y_deg * kPi / 360));
  return rig;
}

Primitive MeshPrimitive(std::shared_ptr<const PlacedMesh> mesh) {
  Primitive p;
  p.type = Primitive::Type::kMesh;
  p.radius = 0;
  p.a = mesh->lo;
  p.b = mesh->hi;
  p.mesh = std::move(mesh);
  return p;
}

Result<Scene> AssetScene(const std::filesystem::path& file) {
  auto placed = PlaceAsset(file, glm::dmat4(1));
  if (!placed) return placed.failure();
  Scene s;
  s.name = file.filename().string();
  Primitive mesh = MeshPrimitive(*placed);
  auto material = MaterialOfMesh((*placed)->mesh.material);
  if (!material) return material.failure();
  s.material = *material;
  // An embedded normal texture is left out here (render --asset frames the
  // asset as it is); a scene file can give it as a file.
  if (!(*placed)->mesh.material.normal_texture.encoded) {
    auto map = NormalMapOfMesh((*placed)->mesh.material, &mesh.normal_map_source);
    if (!map) return map.failure();
    mesh.normal_map = *map;
  }
  auto roughness = RoughnessMapOfMesh((*placed)->mesh.material);
  if (!roughness) return roughness.failure();
  mesh.roughness_map = *roughness;
  s.primitives.push_back(mesh);
  s.light.type = shading::LightType::kDirectional;
  s.light.vec = glm::normalize(glm::dvec3(0.4, 0.8, 0.45));
  const glm::dvec3 centre = ((*placed)->lo + (*placed)->hi) * 0.5;
  double radius = 0;
  for (const glm::vec3& v : (*placed)->mesh.positions) radius = std::max(radius, glm::length(glm::dvec3(v) - centre));
  s.rig = FramingRig(centre, radius, s.rig.fov_y_deg);
  return s;
}

}  // namespace shimmer::scene
