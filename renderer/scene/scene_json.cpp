// Scene files: JSON scenes (docs/scenes.md) read into a Scene, every problem
// named with the file and the JSON Pointer of the key it is about.
#include "shimmer/renderer/scene.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>

#include <glm/gtc/matrix_transform.hpp>

#include "shimmer/core/number_text.h"

namespace shimmer::scene {

namespace {

// Reads the optional fields of one JSON object; the first problem is kept,
// worded with the file and the JSON Pointer (RFC 6901) of the key or object
// it is about: "scene.json: /primitives/2/radius: must be a number > 0".
class FieldReader {
 public:
  // `pointer`: the object's JSON Pointer, "" for the top level.
  FieldReader(const nlohmann::json& object, std::string source, std::string pointer)
      : j_(object), source_(std::move(source)), pointer_(std::move(pointer)) {}

  // `allowed`: every key the object may have; another is reported (a typo
  // would otherwise be ignored silently).
  FieldReader& Keys(std::initializer_list<const char*> allowed) {
    for (const auto& [key, value] : j_.items()) {
      bool known = false;
      for (const char* a : allowed) known = known || key == a;
      if (!known) {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        FailKey(key, "unknown key (expected: " + list + ")");
        break;
      }
    }
    return *this;
  }
  FieldReader& Require(const char* key) {
    if (!j_.contains(key)) FailKey(key, "is required");
    return *this;
  }
  FieldReader& Vec3(const char* key, glm::dvec3* out) {
    if (!ok() || !j_.contains(key)) return *this;
    const auto& v = j_[key];
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
      return FailKey(key, "must be an array of 3 numbers");
    const glm::dvec3 x{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z) || glm::length(x) > kMaxCoordinate)
      return FailKey(key, "must be finite, at most 1e6 from the origin");
    *out = x;
    return *this;
  }
  // A number in [lo, hi] (or (lo, hi] when `open_lo`).
  FieldReader& Number(const char* key, double* out, double lo, double hi, bool open_lo = false) {
    if (!ok() || !j_.contains(key)) return *this;
    const auto& v = j_[key];
    const double x = v.is_number() ? v.get<double>() : std::nan("");
    if (!v.is_number() || !std::isfinite(x) || x < lo || x > hi || (open_lo && x == lo)) {
      std::string range =
          open_lo && lo == 0 ? "> 0" : (open_lo ? "in (" : "in [") + NumberText(lo) + ", " + NumberText(hi) + "]";
      if (open_lo && lo == 0) range += " and <= " + NumberText(hi);
      return FailKey(key, "must be a number " + range);
    }
    *out = x;
    return *this;
  }
  FieldReader& Bool(const char* key, bool* out) {
    if (!ok() || !j_.contains(key)) return *this;
    if (!j_[key].is_boolean()) return FailKey(key, "must be true or false");
    *out = j_[key].get<bool>();
    return *this;
  }
  FieldReader& String(const char* key, std::string* out) {
    if (!ok() || !j_.contains(key)) return *this;
    if (!j_[key].is_string()) return FailKey(key, "must be a string");
    *out = j_[key].get<std::string>();
    return *this;
  }
  // A problem with the value of `key`.
  FieldReader& FailKey(const std::string& key, const std::string& problem) {
    return FailAt(pointer_ + "/" + PointerToken(key), problem);
  }
  // A problem with the object as a whole.
  FieldReader& Fail(const std::string& problem) { return FailAt(pointer_.empty() ? "/" : pointer_, problem); }
  // The first problem another reader (of a nested object) found, already worded.
  FieldReader& Adopt(const std::string& error) {
    if (error_.empty()) error_ = error;
    return *this;
  }
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }

  // RFC 6901 escaping of one reference token: "~" -> "~0", "/" -> "~1".
  static std::string PointerToken(const std::string& key) {
    std::string out;
    for (char c : key) out += c == '~' ? "~0" : (c == '/' ? "~1" : std::string(1, c));
    return out;
  }

 private:
  FieldReader& FailAt(const std::string& pointer, const std::string& problem) {
    if (error_.empty()) error_ = source_ + ": " + pointer + ": " + problem;
    return *this;
  }

  const nlohmann::json& j_;
  std::string source_, pointer_;
  std::string error_;
};

}  // namespace

namespace {

// Total texel words of a scene's maps: word indices are floats in the
// kernel, exact below 2^24.
constexpr std::size_t kMaxNormalMapWords = std::size_t(1) << 24;

// "normal_map": {"file": F | "procedural": NAME, "scale": [u, v], "strength": s}
// on any primitive; a relative file is found beside the scene file.
void ReadNormalMap(FieldReader& r, const nlohmann::json& pj, const std::string& source, const std::string& pointer,
                   Primitive* p) {
  if (!r.ok() || !pj.contains("normal_map")) return;
  const std::string at = pointer + "/normal_map";
  const auto& mj = pj["normal_map"];
  if (!mj.is_object()) {
    r.FailKey("normal_map", "must be an object with 'file' or 'procedural'");
    return;
  }
  FieldReader m(mj, source, at);
  NormalMapSource src;
  m.Keys({"file", "procedural", "scale", "strength"}).String("file", &src.file).String("procedural", &src.procedural);
  m.Number("strength", &src.strength, 0, 10);
  if (m.ok() && src.file.empty() == src.procedural.empty()) m.Fail("needs exactly one of 'file' and 'procedural'");
  if (m.ok() && mj.contains("scale")) {
    const auto& v = mj["scale"];
    const bool pair = v.is_array() && v.size() == 2 && v[0].is_number() && v[1].is_number();
    const glm::dvec2 scale = pair ? glm::dvec2(v[0].get<double>(), v[1].get<double>()) : glm::dvec2(0);
    if (!pair || !(scale.x > 0 && scale.y > 0 && scale.x <= 1e6 && scale.y <= 1e6))
      m.FailKey("scale", "must be an array of 2 numbers in (0, 1e6]: repeats of the map per uv unit");
    else
      p->normal_map_scale = scale;
  }
  if (m.ok() && !src.file.empty() && std::filesystem::path(src.file).is_relative())
    src.file = (std::filesystem::path(source).parent_path() / src.file).string();
  if (m.ok() && p->bump_slope > 0) m.Fail("a plane with 'bump_slope' has its own normal pattern; drop one of them");
  if (!m.ok()) {
    r.Adopt(m.error());
    return;
  }
  auto map = LoadNormalMap(src);
  if (!map) {
    r.Adopt(source + ": " + at + ": " + map.error());
    return;
  }
  p->normal_map = *map;
  p->normal_map_source = src;
}

// "transform": {"translate": [x, y, z], "rotate_deg": [x, y, z], "scale": s or
// [x, y, z]} (scaled, turned about x, then y, then z, then moved), or
// {"matrix": [16 numbers, row by row]}.
void ReadTransform(FieldReader& r, const nlohmann::json& aj, const std::string& source, const std::string& pointer,
                   glm::dmat4* out) {
  if (!r.ok() || !aj.contains("transform")) return;
  const auto& tj = aj["transform"];
  if (!tj.is_object()) {
    r.FailKey("transform", "must be an object with 'translate', 'rotate_deg', 'scale' or 'matrix'");
    return;
  }
  FieldReader t(tj, source, pointer + "/transform");
  t.Keys({"translate", "rotate_deg", "scale", "matrix"});
  if (t.ok() && tj.contains("matrix")) {
    const auto& m = tj["matrix"];
    bool numbers = m.is_array() && m.size() == 16;
    for (std::size_t i = 0; numbers && i < 16; ++i) numbers = m[i].is_number() && std::isfinite(m[i].get<double>());
    if (tj.size() != 1)
      t.Fail("'matrix' stands alone: drop 'translate', 'rotate_deg' and 'scale'");
    else if (!numbers)
      t.FailKey("matrix", "must be an array of 16 finite numbers, row by row");
    else
      for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col) (*out)[col][row] = m[std::size_t(4 * row + col)].get<double>();
    r.Adopt(t.error());
    return;
  }
  glm::dvec3 translate{0}, rotate{0}, scale{1};
  t.Vec3("translate", &translate).Vec3("rotate_deg", &rotate);
  if (t.ok() && tj.contains("scale")) {
    const auto& sj = tj["scale"];
    if (sj.is_number())
      scale = glm::dvec3(sj.get<double>());
    else
      t.Vec3("scale", &scale);
    if (t.ok() && !(glm::all(glm::greaterThan(glm::abs(scale), glm::dvec3(1e-9))) &&
                    glm::all(glm::lessThan(glm::abs(scale), glm::dvec3(1e6)))))
      t.FailKey("scale", "must be a number or 3 numbers, each nonzero and below 1e6 in size");
  }
  if (!t.ok()) {
    r.Adopt(t.error());
    return;
  }
  glm::dmat4 m = glm::translate(glm::dmat4(1), translate);
  m = glm::rotate(m, glm::radians(rotate.z), glm::dvec3(0, 0, 1));
  m = glm::rotate(m, glm::radians(rotate.y), glm::dvec3(0, 1, 0));
  m = glm::rotate(m, glm::radians(rotate.x), glm::dvec3(1, 0, 0));
  *out = glm::scale(m, scale);
}

// "assets": [{"file": F, "transform": T, "material": M, "normal_map": N}]: mesh
// assets (mesh_loading.h) placed beside the primitives; a relative file is
// found beside the scene file. The kernel shades a scene with one material:
// an asset's "material" sets it, so it may be given once, there or at the top.
Status ReadAssets(const nlohmann::json& j, const std::string& source, Scene& s) {
  if (!j.contains("assets")) return Ok();
  const auto& assets = j["assets"];
  if (!assets.is_array() || assets.empty())
    return Status::Failure(source + ": /assets: must be a non-empty array of objects with a 'file'");
  if (s.primitives.size() + assets.size() > kMaxPrimitives)
    return Status::Failure(source + ": /assets: " + std::to_string(s.primitives.size() + assets.size()) +
                           " primitives and assets; at most " + std::to_string(kMaxPrimitives) + " are supported");
  std::string material_at = j.contains("material") ? "/material" : "";
  std::size_t mesh_words = 0;
  int index = 0;
  for (const auto& aj : assets) {
    const std::string pointer = "/assets/" + std::to_string(index++);
    if (!aj.is_object()) return Status::Failure(source + ": " + pointer + ": must be an object with a 'file'");
    FieldReader r(aj, source, pointer);
    std::string file, material;
    r.Keys({"file", "transform", "material", "normal_map"}).Require("file").String("file", &file);
    r.String("material", &material);
    if (r.ok() && file.empty()) r.FailKey("file", "must name a .gltf, .glb or .obj file");
    glm::dmat4 transform(1);
    ReadTransform(r, aj, source, pointer, &transform);
    if (r.ok() && !material.empty() && !material_at.empty())
      r.FailKey("material", "the scene's material is given at " + material_at +
                                " already; a scene has one material, so give it once");
    if (!r.ok()) return Status::Failure(r.error());
    std::filesystem::path path(file);
    if (path.is_relative()) path = std::filesystem::path(source).parent_path() / path;
    auto placed = PlaceAsset(path, transform);
    if (!placed) return Status::Failure(source + ": " + pointer + "/file: " + placed.error());
    Primitive p = MeshPrimitive(*placed);
    ReadNormalMap(r, aj, source, pointer, &p);
    if (!r.ok()) return Status::Failure(r.error());
    if (!aj.contains("normal_map")) {
      auto own = NormalMapOfMesh(p.mesh->mesh.material, &p.normal_map_source);
      if (!own) return Status::Failure(source + ": " + pointer + "/file: " + own.error());
      p.normal_map = *own;
    }
    auto roughness = RoughnessMapOfMesh(p.mesh->mesh.material);
    if (!roughness) return Status::Failure(source + ": " + pointer + "/file: " + roughness.error());
    p.roughness_map = *roughness;
    // Neither the scene nor an entry before gives the material: the first
    // asset's own.
    if (material.empty() && material_at.empty() && index == 1) {
      auto own = MaterialOfMesh(p.mesh->mesh.material);
      if (!own) return Status::Failure(source + ": " + pointer + "/file: " + own.error());
      s.material = *own;
    }
    if (!material.empty()) {
      auto m = ParseMaterial(material, s.material);
      if (!m) return Status::Failure(source + ": " + pointer + "/material: " + m.error());
      s.material = *m;
      material_at = pointer + "/material";
    }
    mesh_words += PackedMeshWords(*p.mesh) + (p.roughness_map ? PackedRoughnessWords(*p.roughness_map) : 0);
    if (mesh_words >= kMaxSceneWords)
      return Status::Failure(source + ": /assets: the assets up to " + pointer +
                             " take more than the kernel's 2^24 scene words; use smaller assets");
    s.primitives.push_back(p);
  }
  return Ok();
}

}  // namespace

namespace {

// The analytic primitive at `pointer` ("/primitives/3").
Result<Primitive> PrimitiveFromJson(const nlohmann::json& pj, const std::string& source, const std::string& pointer) {
  using R = Result<Primitive>;
  if (!pj.is_object()) return R::Failure(source + ": " + pointer + ": must be an object with a 'type'");
  FieldReader r(pj, source, pointer);
  std::string type;
  r.Require("type").String("type", &type);
  if (!r.ok()) return R::Failure(r.error());
  Primitive p;
  if (type == "sphere") {
    p.type = Primitive::Type::kSphere;
    r.Keys({"type", "center", "radius", "normal_map"}).Require("center");
    r.Vec3("center", &p.a).Number("radius", &p.radius, 0, kMaxCoordinate, true);
  } else if (type == "capsule") {
    p.type = Primitive::Type::kCapsule;
    p.radius = 0.02;
    r.Keys({"type", "a", "b", "radius", "normal_map"}).Require("a").Require("b");
    r.Vec3("a", &p.a).Vec3("b", &p.b).Number("radius", &p.radius, 0, kMaxCoordinate, true);
    if (r.ok() && glm::length(p.b - p.a) < 1e-9) r.FailKey("b", "coincides with 'a': a capsule needs two ends");
  } else if (type == "plane") {
    p.type = Primitive::Type::kPlane;
    p.radius = 0;
    r.Keys({"type", "height", "bump_slope", "bump_frequency", "normal_map"});
    r.Number("height", &p.radius, -kMaxCoordinate, kMaxCoordinate)
        .Number("bump_slope", &p.bump_slope, 0, 10)
        .Number("bump_frequency", &p.bump_frequency, 0, 1e4);
    if (r.ok() && p.bump_slope > 0 && p.bump_frequency <= 0)
      r.FailKey("bump_frequency", "must be > 0 when 'bump_slope' is");
  } else {
    r.FailKey("type", "unknown type '" + type + "' (sphere, capsule, plane)");
  }
  ReadNormalMap(r, pj, source, pointer, &p);
  if (!r.ok()) return R::Failure(r.error());
  return p;
}

// The kernel reads every normal map's mip chain from the scene words: their
// texels, each map once however many primitives share it, are bounded.
Status CheckNormalMapWords(const std::vector<Primitive>& primitives, const std::string& source) {
  std::vector<const NormalMap*> maps;
  std::size_t map_words = 0;
  for (const Primitive& p : primitives)
    if (p.normal_map && std::find(maps.begin(), maps.end(), p.normal_map.get()) == maps.end()) {
      maps.push_back(p.normal_map.get());
      for (const NormalMapLevel& level : p.normal_map->levels) map_words += 3 * level.texels.size();
    }
  if (map_words > kMaxNormalMapWords)
    return Status::Failure(source + ": /primitives: the normal maps' mip chains take " + std::to_string(map_words / 3) +
                           " texels; at most " + std::to_string(kMaxNormalMapWords / 3) +
                           " fit (about one 2048 x 2048 map; use smaller maps)");
  return Ok();
}

// "/light": directional (the default), sphere or sg.
Status ReadLight(const nlohmann::json& lj, const std::string& source, shading::LightDesc* light) {
  if (!lj.is_object()) return Status::Failure(source + ": /light: must be an object");
  std::string type = "directional";
  FieldReader r(lj, source, "/light");
  r.String("type", &type);
  if (r.ok() && type == "directional") {
    glm::dvec3 dir{0, 1, 0}, rad{1, 1, 1};
    r.Keys({"type", "direction", "irradiance", "shadows"})
        .Vec3("direction", &dir)
        .Vec3("irradiance", &rad)
        .Bool("shadows", &light->shadows);
    if (r.ok() && glm::length(dir) < 1e-9) r.FailKey("direction", "must not be zero");
    if (r.ok() && glm::any(glm::lessThan(rad, glm::dvec3(0)))) r.FailKey("irradiance", "must be >= 0");
    light->type = shading::LightType::kDirectional;
    if (r.ok()) light->vec = glm::normalize(dir);
    light->radiance = rad;
  } else if (r.ok() && type == "sphere") {
    light->type = shading::LightType::kSphere;
    light->radius = 0.05;
    r.Keys({"type", "center", "intensity", "radius", "shadows"})
        .Vec3("center", &light->vec)
        .Vec3("intensity", &light->radiance)
        .Number("radius", &light->radius, 1e-6, kMaxCoordinate)
        .Bool("shadows", &light->shadows);
    if (r.ok() && glm::any(glm::lessThan(light->radiance, glm::dvec3(0)))) r.FailKey("intensity", "must be >= 0");
  } else if (r.ok() && type == "sg") {
    // A distant spherical Gaussian (seed 004): amplitude e^(sharpness (axis.l - 1)).
    glm::dvec3 axis{0, 1, 0}, amplitude{1, 1, 1};
    double sharpness = 0;
    if (lj.contains("shadows"))
      r.FailKey("shadows", "an SG light is a distant lobe over the whole sky and casts no hard shadow; "
                           "use a directional or sphere light");
    r.Keys({"type", "axis", "sharpness", "amplitude"})
        .Require("axis")
        .Require("sharpness")
        .Require("amplitude")
        .Vec3("axis", &axis)
        .Number("sharpness", &sharpness, 0, kMaxSgSharpness)
        .Vec3("amplitude", &amplitude);
    if (r.ok() && glm::length(axis) < 1e-9) r.FailKey("axis", "must not be zero");
    if (r.ok() && glm::any(glm::lessThan(amplitude, glm::dvec3(0)))) r.FailKey("amplitude", "must be >= 0");
    light->type = shading::LightType::kSg;
    if (r.ok()) light->vec = glm::normalize(axis);
    light->radius = sharpness;
    light->radiance = amplitude;
  } else if (r.ok()) {
    r.FailKey("type", "must be directional, sphere or sg, got '" + type + "'");
  }
  if (!r.ok()) return Status::Failure(r.error());
  return Ok();
}

// "/camera": the rig the camera paths start from.
Status ReadCameraRig(const nlohmann::json& cj, const std::string& source, CameraRig* rig) {
  if (!cj.is_object()) return Status::Failure(source + ": /camera: must be an object");
  FieldReader r(cj, source, "/camera");
  r.Keys({"target", "distance", "elevation_deg", "azimuth_deg", "fov_y_deg"})
      .Vec3("target", &rig->target)
      .Number("distance", &rig->distance, 1e-6, kMaxCoordinate)
      .Number("elevation_deg", &rig->elevation_deg, -89, 89)
      .Number("azimuth_deg", &rig->azimuth_deg, -1e6, 1e6)
      .Number("fov_y_deg", &rig->fov_y_deg, 1, 170);
  if (!r.ok()) return Status::Failure(r.error());
  return Ok();
}

}  // namespace

Result<Scene> SceneFromJson(const nlohmann::json& j, const std::string& source) {
  using R = Result<Scene>;
  if (!j.is_object()) return R::Failure(source + ": /: a scene is a JSON object");
  Scene s;
  s.name = source;
  FieldReader top(j, source, "");
  top.Keys({"name", "geometry_class", "primitives", "assets", "light", "material", "camera"})
      .String("name", &s.name)
      .String("geometry_class", &s.geometry_class);
  if (top.ok() && j.contains("geometry_class") && s.geometry_class.empty())
    return R::Failure(source + ": /geometry_class: must be a non-empty string");
  if (top.ok() && !j.contains("assets")) top.Require("primitives");
  if (!top.ok()) return R::Failure(top.error());
  const nlohmann::json no_primitives = nlohmann::json::array();
  const auto& prims = j.contains("primitives") ? j["primitives"] : no_primitives;
  if (!prims.is_array() || (prims.empty() && j.contains("primitives")))
    return R::Failure(source + ": /primitives: must be a non-empty array");
  if (prims.size() > kMaxPrimitives)
    return R::Failure(source + ": /primitives: " + std::to_string(prims.size()) + " primitives; at most " +
                      std::to_string(kMaxPrimitives) + " are supported");
  int index = 0;
  for (const auto& pj : prims) {
    auto p = PrimitiveFromJson(pj, source, "/primitives/" + std::to_string(index++));
    if (!p) return p.failure();
    s.primitives.push_back(std::move(*p));
  }
  if (Status m = CheckNormalMapWords(s.primitives, source); !m) return m.failure();
  if (j.contains("light"))
    if (Status l = ReadLight(j["light"], source, &s.light); !l) return l.failure();
  if (j.contains("material")) {
    if (!j["material"].is_string()) return R::Failure(source + ": /material: must be a spec string like \"ggx:0.05\"");
    auto m = ParseMaterial(j["material"].get<std::string>(), s.material);
    if (!m) return R::Failure(source + ": /material: " + m.error());
    s.material = *m;
  }
  if (j.contains("camera"))
    if (Status c = ReadCameraRig(j["camera"], source, &s.rig); !c) return c.failure();
  if (Status a = ReadAssets(j, source, s); !a) return a.failure();
  return s;
}

}  // namespace shimmer::scene
