// Scenes of analytic primitives (built in or from a small JSON file), the
// --material spec, camera paths, and the packed form the kernel reads.
#pragma once

#include <glm/glm.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "shimmer/core/result.h"
#include "shimmer/renderer/normal_map.h"
#include "shimmer/renderer/triangle_bvh.h"
#include "shimmer/shading/shading.h"

namespace shimmer::scene {

// A mesh asset placed in a scene (PlaceAsset): its meshes merged into one in
// world space, with the BVH the kernel walks (scene.glsl, "Meshes").
struct PlacedMesh {
  std::filesystem::path file;
  std::string content_hash;  // AssetContentHash: a job's id hashes it (FingerprintRender)
  glm::dmat4 transform{1};
  TriangleMesh mesh;  // its material is the first mesh's
  TriangleBvh bvh;
  glm::dvec3 lo{0}, hi{0};  // bounds
  std::vector<std::string> warnings;  // the loader's
};

// The kernel's word indices are floats, exact below 2^24; its BVH stack
// (scene.glsl MESH_STACK) holds this many levels.
inline constexpr std::size_t kMaxSceneWords = std::size_t(1) << 24;
inline constexpr int kMaxMeshBvhDepth = 100;

// `file` loaded, moved by `transform` (meshes, normals and tangents), merged
// and its BVH built; kept per process by the asset's content hash and the
// transform. Errors name the file: the loader's, a singular transform, an
// asset of zero-area triangles only, one too large for the kernel's words.
Result<std::shared_ptr<const PlacedMesh>> PlaceAsset(const std::filesystem::path& file, const glm::dmat4& transform);
// The words PackScene writes for the mesh.
std::size_t PackedMeshWords(const PlacedMesh& mesh);

// A mesh's roughness texture as the kernel reads it (scene.glsl, "Roughness
// textures"): per texel the factor (G / mean G)^2 by which the material's
// alpha is scaled there, row 0 at v = 0 (glTF's uv), repeating.
struct RoughnessMap {
  int width = 0, height = 0;
  std::vector<float> alpha_factor;  // width x height, row by row
};
// The words PackScene writes for it: a header, then four texels a word.
std::size_t PackedRoughnessWords(const RoughnessMap& map);

struct Primitive {
  // kMesh: a placed asset; a and b hold its bounds.
  enum class Type { kSphere = 0, kCapsule = 1, kPlane = 2, kMesh = 3 };
  Type type = Type::kSphere;
  glm::dvec3 a{0};    // sphere centre, capsule end
  glm::dvec3 b{0};    // capsule end
  double radius = 1;  // sphere, capsule; plane: height y
  double bump_slope = 0;
  double bump_frequency = 0;
  // A tangent-space normal map over the primitive's uv (scene.glsl), repeated
  // `normal_map_scale` times per uv unit; null: none.
  std::shared_ptr<const NormalMap> normal_map;
  NormalMapSource normal_map_source;
  glm::dvec2 normal_map_scale{1, 1};
  std::shared_ptr<const PlacedMesh> mesh;  // kMesh
  // kMesh: the asset's roughness texture (RoughnessMapOfMesh); null: none.
  std::shared_ptr<const RoughnessMap> roughness_map;
};

// Where the camera paths start: looking at `target` from `distance`, at
// `elevation_deg` above the horizon and `azimuth_deg` around +y.
struct CameraRig {
  glm::dvec3 target{0};
  double distance = 4;
  double elevation_deg = 15;
  double azimuth_deg = 0;
  double fov_y_deg = 30;
};

struct Scene {
  std::string name;
  // The row of the report's answer its shots belong to ("low-poly mesh"),
  // where the scene file names one; empty: the report classes it itself.
  std::string geometry_class;
  std::vector<Primitive> primitives;
  shading::LightDesc light;
  shading::MaterialDesc material;  // the default; --material overrides it
  CameraRig rig;
};

// Limits of a scene file: the BVH build recurses, and coordinates beyond
// these lose every digit of a float in the kernel.
inline constexpr std::size_t kMaxPrimitives = 1 << 20;
inline constexpr double kMaxCoordinate = 1e6;
// An SG light's sharpness: beyond it the lobe is narrower than float's
// angular resolution near the axis (1 - cos below 1e-7).
inline constexpr double kMaxSgSharpness = 1e6;

// A scene of one asset for `shimmer render --asset`: the asset as it is,
// lit by a directional key light from above and in front, the default
// material, and a rig that frames it (FramingRig of the sphere about its
// bounds' centre through its farthest vertex).
Result<Scene> AssetScene(const std::filesystem::path& file);
// The scene primitive of a placed mesh: its bounds as a and b.
Primitive MeshPrimitive(std::shared_ptr<const PlacedMesh> mesh);
// An asset's own material as the scene's (used where neither the scene nor
// the asset entry gives one): glTF's metallic-roughness model (glTF 2.0 spec,
// Appendix B) as GGX with alpha = roughness^2, f0 = mix(0.04, base colour,
// metallic) and diffuse albedo = base colour * (1 - metallic). A roughness
// texture (glTF: G; MTL map_Pr: its one channel) multiplies the factor by
// its mean over the image: the material's alpha is the texture's mean, and
// RoughnessMapOfMesh its variation.
Result<shading::MaterialDesc> MaterialOfMesh(const MeshMaterial& m);
// The mesh's roughness texture as per-texel factors (G / mean G)^2 of
// whichever material's alpha shades the mesh (its own or a scene's or the
// command line's): the glTF roughness r x G, squared, over its mean. Null
// when the mesh has no roughness texture or one without variation.
Result<std::shared_ptr<const RoughnessMap>> RoughnessMapOfMesh(const MeshMaterial& m);
// The asset's normal texture as a normal map (its glTF `scale` as the
// strength), where the asset entry names none: null when the mesh has no
// normal texture. An embedded image (data URI, GLB) is refused with a
// message that says to give `normal_map` a file.
Result<std::shared_ptr<const NormalMap>> NormalMapOfMesh(const MeshMaterial& m, NormalMapSource* source);
// Looking at `centre` from 20 degrees above and 30 around, far enough that
// the sphere of `radius` about it fills 90 % of the vertical field of view.
CameraRig FramingRig(glm::dvec3 centre, double radius, double fov_y_deg);

std::vector<std::string_view> BuiltinSceneNames();
// A built-in name, or else a path to a JSON scene file. Errors name the file
// and the JSON Pointer of the key ("s.json: /primitives/0/center: is required").
Result<Scene> LoadScene(const std::string& name_or_file);
Result<Scene> ParseSceneJson(std::string_view text, const std::string& source);
Result<Scene> SceneFromJson(const nlohmann::json& json, const std::string& source);

// NDF:ALPHA[,ALPHA_Y][,f0=V|R/G/B][,albedo=V|R/G/B], e.g. "ggx:0.05",
// "beckmann:0.02,0.1,f0=0.9/0.6/0.3,albedo=0". Unset fields keep `base`'s.
Result<shading::MaterialDesc> ParseMaterial(std::string_view spec, const shading::MaterialDesc& base);
std::string MaterialSpec(const shading::MaterialDesc& m);

// The words of scene.glsl's layout, BVH included.
std::vector<glm::vec4> PackScene(const Scene& scene);
// The SCENE_* bit mask of scene.glsl: which primitive kinds the scene holds,
// so that the kernel is specialised to them.
int SceneFeatures(const Scene& scene);

// --- camera paths -------------------------------------------------------------

enum class CameraPath { kOrbit, kPan, kDolly, kVrJitter, kStatic };
std::vector<std::string_view> CameraPathNames();
std::optional<CameraPath> ParseCameraPath(std::string_view name);
std::string_view CameraPathName(CameraPath path);
// The camera of `path` at time `frame / fps` seconds; deterministic.
shading::CameraDesc CameraAt(CameraPath path, const CameraRig& rig, int frame, double fps, int width, int height);

}  // namespace shimmer::scene
