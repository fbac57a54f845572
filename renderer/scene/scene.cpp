#include "shimmer/renderer/scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>

#include "shimmer/core/json_file.h"
#include "shimmer/core/number_text.h"

namespace shimmer::scene {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Deterministic [0, 1) from an integer (built-in scenes must not depend on a RNG library).
double Hash01(std::uint32_t v) {
  v ^= v >> 16;
  v *= 0x7feb352dU;
  v ^= v >> 15;
  v *= 0x846ca68bU;
  v ^= v >> 16;
  return double(v >> 8) / double(1u << 24);
}

shading::LightDesc Directional(glm::dvec3 towards, double irradiance) {
  shading::LightDesc l;
  l.type = shading::LightType::kDirectional;
  l.vec = glm::normalize(towards);
  l.radiance = glm::dvec3(irradiance);
  return l;
}

// An SG light with the same irradiance at normal incidence as a directional
// light of `irradiance`: int a e^(lambda (cos - 1)) cos dw = E gives
// a = E lambda / (2 pi (1 - e^(-2 lambda))) up to the lobe's curvature
// (1 / lambda relative).
shading::LightDesc SgLight(glm::dvec3 axis, double sharpness, double irradiance) {
  shading::LightDesc l;
  l.type = shading::LightType::kSg;
  l.vec = glm::normalize(axis);
  l.radius = sharpness;
  l.radiance = glm::dvec3(irradiance * sharpness / (2 * kPi * -std::expm1(-2 * sharpness)));
  return l;
}

// Sharpness of the built-in SG scenes' lights: a lobe of about 4 degrees
// (1 / sqrt(lambda) radians), between a sun and the broad SGs of baked
// ambient light, sharp enough that the highlights of glossy materials still
// alias.
constexpr double kBuiltinSgSharpness = 200;
// A glint material's defaults: a microdetail's lobe, and microdetails per
// unit area (a level-0 glint cell is 1 / sqrt(density) wide).
constexpr double kDefaultGlintAlphaL = 0.03;
constexpr double kDefaultGlintDensity = 1e4;
constexpr double kMaxGlintDensity = 1e12;

// Primitives of the built-in scenes, every other field at its default.
Primitive SpherePrimitive(glm::dvec3 centre, double radius) {
  Primitive p;
  p.type = Primitive::Type::kSphere;
  p.a = centre;
  p.radius = radius;
  return p;
}
Primitive CapsulePrimitive(glm::dvec3 a, glm::dvec3 b, double radius) {
  Primitive p;
  p.type = Primitive::Type::kCapsule;
  p.a = a, p.b = b;
  p.radius = radius;
  return p;
}
Primitive PlanePrimitive(double height) {
  Primitive p;
  p.type = Primitive::Type::kPlane;
  p.radius = height;
  return p;
}

Scene SphereScene() {
  Scene s;
  s.name = "sphere";
  s.primitives.push_back(SpherePrimitive({0, 0, 0}, 1.0));
  s.light = Directional({-0.5, 0.6, 0.8}, 3.0);
  s.material.alpha = {0.05, 0.05};
  s.rig = {{0, 0, 0}, 4.0, 15.0, 0.0, 35.0};
  return s;
}

// Many sub-pixel to few-pixel spheres on a ground plane.
Scene SphereFieldScene() {
  Scene s;
  s.name = "sphere-field";
  const int n = 12;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      std::uint32_t id = std::uint32_t(j * n + i);
      double r = 0.03 + 0.22 * Hash01(id * 3 + 1) * Hash01(id * 3 + 2);
      double x = -3.0 + 6.0 * (i + 0.5) / n + 0.15 * (Hash01(id * 7 + 3) - 0.5);
      double z = -3.0 + 6.0 * (j + 0.5) / n + 0.15 * (Hash01(id * 7 + 4) - 0.5);
      s.primitives.push_back(SpherePrimitive({x, r, z}, r));
    }
  s.primitives.push_back(PlanePrimitive(0.0));
  s.light = Directional({-0.4, 0.7, 0.6}, 3.0);
  s.material.alpha = {0.03, 0.03};
  s.rig = {{0, 0, 0}, 8.0, 35.0, 20.0, 45.0};
  return s;
}

// Thin capsules crossing in a box: hair-like highlights under a small sphere light.
Scene WiresScene() {
  Scene s;
  s.name = "wires";
  for (int i = 0; i < 32; ++i) {
    std::uint32_t id = std::uint32_t(i);
    double y = -0.8 + 1.6 * (i + 0.5) / 32.0;
    double phi = 2 * kPi * Hash01(id * 5 + 1);
    glm::dvec3 c{0.3 * (Hash01(id * 5 + 2) - 0.5), y, 0.3 * (Hash01(id * 5 + 3) - 0.5)};
    glm::dvec3 d{std::cos(phi), 0.25 * (Hash01(id * 5 + 4) - 0.5), std::sin(phi)};
    d = glm::normalize(d) * 1.2;
    double r = 0.006 + 0.012 * Hash01(id * 5 + 5);
    s.primitives.push_back(CapsulePrimitive(c - d, c + d, r));
  }
  s.light.type = shading::LightType::kSphere;
  s.light.vec = {-1.5, 2.5, 2.5};
  s.light.radius = 0.1;
  s.light.radiance = glm::dvec3(30.0);
  s.material.alpha = {0.04, 0.2};
  s.rig = {{0, 0, 0}, 4.5, 10.0, 0.0, 40.0};
  return s;
}

// A plane with a procedural normal pattern seen at a grazing angle.
Scene BumpyPlaneScene() {
  Scene s;
  s.name = "bumpy-plane";
  Primitive p;
  p.type = Primitive::Type::kPlane;
  p.radius = 0.0;
  p.bump_slope = 0.12;
  p.bump_frequency = 14.0;
  s.primitives.push_back(p);
  s.light = Directional({0.0, 0.25, -1.0}, 3.0);  // low, facing the camera: a long glint
  s.material.alpha = {0.02, 0.02};
  s.rig = {{0, 0, 0}, 6.0, 10.0, 0.0, 40.0};
  return s;
}

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

bool ParseRgb(std::string_view text, glm::dvec3* out) {
  std::vector<double> v;
  std::string s(text);
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, '/')) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(item, &used);
    } catch (const std::exception&) {
      return false;
    }
    if (used != item.size() || !std::isfinite(x) || x < 0) return false;
    v.push_back(x);
  }
  if (v.size() == 1)
    *out = glm::dvec3(v[0]);
  else if (v.size() == 3)
    *out = {v[0], v[1], v[2]};
  else
    return false;
  return true;
}

// --- BVH --------------------------------------------------------------------

struct Box {
  glm::dvec3 lo{1e300}, hi{-1e300};
  void Add(const Box& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
};

Box Bounds(const Primitive& p) {
  Box b;
  glm::dvec3 r(p.radius);
  if (p.type == Primitive::Type::kSphere) return {p.a - r, p.a + r};
  b.lo = glm::min(p.a, p.b) - r;
  b.hi = glm::max(p.a, p.b) + r;
  return b;
}

struct BvhNode {
  Box box;
  int skip = 0;   // the node after this subtree
  int prim = -1;  // a leaf's one primitive; -1: interior
};

// Median split on the widest centroid axis, nodes appended in depth-first
// order (scene.glsl walks them without a stack).
void BuildNode(std::vector<BvhNode>& nodes, std::vector<int>& order, int begin, int end,
               const std::vector<Primitive>& prims) {
  const int index = static_cast<int>(nodes.size());
  nodes.emplace_back();
  Box box, centroids;
  for (int i = begin; i < end; ++i) {
    Box b = Bounds(prims[order[i]]);
    box.Add(b);
    glm::dvec3 c = (b.lo + b.hi) * 0.5;
    centroids.Add({c, c});
  }
  nodes[index].box = box;
  if (end - begin == 1) {
    nodes[index].prim = begin;
  } else {
    glm::dvec3 ext = centroids.hi - centroids.lo;
    int axis = ext.x > ext.y ? (ext.x > ext.z ? 0 : 2) : (ext.y > ext.z ? 1 : 2);
    int mid = (begin + end) / 2;
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, [&](int a, int b) {
      Box ba = Bounds(prims[a]), bb = Bounds(prims[b]);
      return ba.lo[axis] + ba.hi[axis] < bb.lo[axis] + bb.hi[axis];
    });
    BuildNode(nodes, order, begin, mid, prims);
    BuildNode(nodes, order, mid, end, prims);
  }
  nodes[index].skip = static_cast<int>(nodes.size());
}

glm::vec4 PrimWord0(const Primitive& p) {
  return {float(static_cast<int>(p.type)), float(p.radius), float(p.bump_slope), float(p.bump_frequency)};
}

// The SG-lit scenes (seed 004): delta-lit ones with their light made an SG
// of the same axis and irradiance, and a smooth grazing plane.
Scene SgSphereFieldScene() {
  Scene s = SphereFieldScene();
  s.name = "sg-sphere-field";
  s.light = SgLight(s.light.vec, kBuiltinSgSharpness, 3.0);
  return s;
}

Scene SgBumpyPlaneScene() {
  Scene s = BumpyPlaneScene();
  s.name = "sg-bumpy-plane";
  s.light = SgLight(s.light.vec, kBuiltinSgSharpness, 3.0);
  return s;
}

// A smooth plane at grazing view with the light low in front of the camera:
// the stretched highlight that the ASG warp models and the SG warp makes round.
Scene SgPlaneScene() {
  Scene s;
  s.name = "sg-plane";
  s.primitives.push_back(PlanePrimitive(0.0));
  s.light = SgLight({0.0, 0.2, -1.0}, kBuiltinSgSharpness, 3.0);
  s.material.alpha = {0.1, 0.1};
  s.rig = {{0, 0, 0}, 6.0, 10.0, 0.0, 40.0};
  return s;
}

// A built-in procedural normal map (they are generated, so cannot fail to load).
std::shared_ptr<const NormalMap> Procedural(const std::string& name) {
  NormalMapSource src;
  src.procedural = name;
  return LoadNormalMap(src).value();
}

Primitive WithMap(Primitive p, const std::string& map, glm::dvec2 scale) {
  p.normal_map = Procedural(map);
  p.normal_map_source.procedural = map;
  p.normal_map_scale = scale;
  return p;
}

// Seed 003's case: bumpy detail in a normal map seen at a distance. A
// grazing plane receding from a few texels per pixel (at 96 x 96) near the
// camera to hundreds far away, the light low in front of the camera.
Scene NmPlaneScene() {
  Scene s;
  s.name = "nm-plane";
  s.primitives.push_back(WithMap(PlanePrimitive(0.0), "bumps", {0.25, 0.25}));
  s.light = Directional({0.0, 0.35, -1.0}, 3.0);
  s.material.alpha = {0.05, 0.05};
  s.rig = {{0, 0, 0}, 6.0, 12.0, 0.0, 40.0};
  return s;
}

// A normal-mapped sphere: the fine bumps minified several texels per pixel.
Scene NmSphereScene() {
  Scene s;
  s.name = "nm-sphere";
  s.primitives.push_back(WithMap(SpherePrimitive({0, 0, 0}, 1.0), "bumps-fine", {4, 2}));
  s.light = Directional({-0.5, 0.6, 0.8}, 3.0);
  s.material.alpha = {0.05, 0.05};
  s.rig = {{0, 0, 0}, 4.0, 15.0, 0.0, 35.0};
  return s;
}

// Magnification: a close plane whose texels span several pixels, where
// bilinear Toksvig and LEAN turn blocky and the Gaussian-baked Toksvig map
// does not (seed 003, Figures 3a and 3b).
Scene NmMagnifyScene() {
  Scene s;
  s.name = "nm-magnify";
  s.primitives.push_back(WithMap(PlanePrimitive(0.0), "bumps", {0.02, 0.02}));
  s.light = Directional({0.0, 0.8, -0.6}, 3.0);
  s.material.alpha = {0.05, 0.05};
  s.rig = {{0, 0, 0}, 2.0, 45.0, 0.0, 40.0};
  return s;
}

shading::MaterialDesc GlintMaterial(glm::dvec2 alpha, double alpha_l, double density, double albedo) {
  shading::MaterialDesc m;
  m.ndf = shading::Ndf::kGlints;
  m.alpha = alpha;
  m.glint_alpha_l = alpha_l;
  m.glint_density = density;
  m.albedo = glm::dvec3(albedo);
  return m;
}

// Seed 001's snow: a glittering plane receding from the camera at a grazing
// angle, the light low in front of it, so that the footprint grows from a
// few microdetails per pixel near the camera (96 x 96) to thousands far away.
Scene GlintPlaneScene() {
  Scene s;
  s.name = "glint-plane";
  s.primitives.push_back(PlanePrimitive(0.0));
  s.light = Directional({0.0, 0.35, -1.0}, 3.0);
  s.material = GlintMaterial({0.3, 0.3}, 0.03, 1e4, 0.3);
  s.rig = {{0, 0, 0}, 6.0, 12.0, 0.0, 40.0};
  return s;
}

// A glittering sphere: isotropic footprints in its middle, grazing and
// anisotropic ones at the silhouette.
Scene GlintSphereScene() {
  Scene s;
  s.name = "glint-sphere";
  s.primitives.push_back(SpherePrimitive({0, 0, 0}, 1.0));
  s.light = Directional({-0.5, 0.6, 0.8}, 3.0);
  s.material = GlintMaterial({0.2, 0.2}, 0.02, 1e5, 0.3);
  s.rig = {{0, 0, 0}, 4.0, 15.0, 0.0, 35.0};
  return s;
}

}  // namespace

std::vector<std::string_view> BuiltinSceneNames() {
  return {"sphere",          "sphere-field",   "wires",    "bumpy-plane", "sg-sphere-field", "sg-plane",
          "sg-bumpy-plane",  "nm-plane",       "nm-sphere", "nm-magnify", "glint-plane",     "glint-sphere"};
}

namespace {

// "SCENE@MAP": a fit per map (and any spec) renders one scene's geometry,
// light and rig with each of several maps, without a scene file per map.
Result<Scene> SceneWithMap(const std::string& name, std::size_t at) {
  const std::string base = name.substr(0, at), map = name.substr(at + 1);
  if (base.empty() || map.empty())
    return Result<Scene>::Failure("scene '" + name + "': SCENE@MAP needs both a scene and a normal map");
  auto scene = LoadScene(base);
  if (!scene) return scene.failure();
  bool procedural = false;
  for (auto n : ProceduralNormalMapNames()) procedural |= n == map;
  int replaced = 0;
  for (Primitive& p : scene->primitives) {
    if (!p.normal_map) continue;
    NormalMapSource source;
    source.strength = p.normal_map_source.strength;
    (procedural ? source.procedural : source.file) = map;
    auto loaded = LoadNormalMap(source);
    if (!loaded) return Result<Scene>::Failure("scene '" + name + "': " + loaded.error());
    p.normal_map = *loaded;
    p.normal_map_source = source;
    ++replaced;
  }
  if (replaced == 0)
    return Result<Scene>::Failure("scene '" + name + "': '" + base + "' has no normal map for '" + map +
                                  "' to replace");
  scene->name = name;
  return scene;
}

}  // namespace

Result<Scene> LoadScene(const std::string& name) {
  std::error_code exists_ec;
  if (const std::size_t at = name.rfind('@');
      at != std::string::npos && !std::filesystem::is_regular_file(name, exists_ec))
    return SceneWithMap(name, at);
  if (name == "sphere") return SphereScene();
  if (name == "sphere-field") return SphereFieldScene();
  if (name == "wires") return WiresScene();
  if (name == "bumpy-plane") return BumpyPlaneScene();
  if (name == "sg-sphere-field") return SgSphereFieldScene();
  if (name == "sg-plane") return SgPlaneScene();
  if (name == "sg-bumpy-plane") return SgBumpyPlaneScene();
  if (name == "nm-plane") return NmPlaneScene();
  if (name == "nm-sphere") return NmSphereScene();
  if (name == "nm-magnify") return NmMagnifyScene();
  if (name == "glint-plane") return GlintPlaneScene();
  if (name == "glint-sphere") return GlintSphereScene();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(name, ec)) {
    std::string list;
    for (auto n : BuiltinSceneNames()) list += (list.empty() ? "" : ", ") + std::string(n);
    return Result<Scene>::Failure("unknown scene '" + name + "': not a built-in scene (" + list +
                                  ") nor a JSON scene file");
  }
  auto json = ReadJsonFile(name);
  if (!json) return json.failure();
  return SceneFromJson(*json, name);
}

Result<Scene> ParseSceneJson(std::string_view text, const std::string& source) {
  auto json = ParseJson(text, source);
  if (!json) return json.failure();
  return SceneFromJson(*json, source);
}

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

}  // namespace

Result<Scene> SceneFromJson(const nlohmann::json& j, const std::string& source) {
  using R = Result<Scene>;
  if (!j.is_object()) return R::Failure(source + ": /: a scene is a JSON object");
  Scene s;
  s.name = source;
  FieldReader top(j, source, "");
  top.Keys({"name", "primitives", "light", "material", "camera"}).String("name", &s.name).Require("primitives");
  if (!top.ok()) return R::Failure(top.error());
  const auto& prims = j["primitives"];
  if (!prims.is_array() || prims.empty()) return R::Failure(source + ": /primitives: must be a non-empty array");
  if (prims.size() > kMaxPrimitives)
    return R::Failure(source + ": /primitives: " + std::to_string(prims.size()) + " primitives; at most " +
                      std::to_string(kMaxPrimitives) + " are supported");
  int index = 0;
  for (const auto& pj : prims) {
    const std::string pointer = "/primitives/" + std::to_string(index++);
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
    s.primitives.push_back(p);
  }
  std::vector<const NormalMap*> maps;
  std::size_t map_words = 0;
  for (const Primitive& p : s.primitives)
    if (p.normal_map && std::find(maps.begin(), maps.end(), p.normal_map.get()) == maps.end()) {
      maps.push_back(p.normal_map.get());
      for (const NormalMapLevel& level : p.normal_map->levels) map_words += 3 * level.texels.size();
    }
  if (map_words > kMaxNormalMapWords)
    return R::Failure(source + ": /primitives: the normal maps' mip chains take " + std::to_string(map_words / 3) +
                      " texels; at most " + std::to_string(kMaxNormalMapWords / 3) +
                      " fit (about one 2048 x 2048 map; use smaller maps)");
  if (j.contains("light")) {
    const auto& lj = j["light"];
    if (!lj.is_object()) return R::Failure(source + ": /light: must be an object");
    std::string type = "directional";
    FieldReader r(lj, source, "/light");
    r.String("type", &type);
    if (r.ok() && type == "directional") {
      glm::dvec3 dir{0, 1, 0}, rad{1, 1, 1};
      r.Keys({"type", "direction", "irradiance"}).Vec3("direction", &dir).Vec3("irradiance", &rad);
      if (r.ok() && glm::length(dir) < 1e-9) r.FailKey("direction", "must not be zero");
      if (r.ok() && glm::any(glm::lessThan(rad, glm::dvec3(0)))) r.FailKey("irradiance", "must be >= 0");
      s.light.type = shading::LightType::kDirectional;
      if (r.ok()) s.light.vec = glm::normalize(dir);
      s.light.radiance = rad;
    } else if (r.ok() && type == "sphere") {
      s.light.type = shading::LightType::kSphere;
      s.light.radius = 0.05;
      r.Keys({"type", "center", "intensity", "radius"})
          .Vec3("center", &s.light.vec)
          .Vec3("intensity", &s.light.radiance)
          .Number("radius", &s.light.radius, 1e-6, kMaxCoordinate);
      if (r.ok() && glm::any(glm::lessThan(s.light.radiance, glm::dvec3(0)))) r.FailKey("intensity", "must be >= 0");
    } else if (r.ok() && type == "sg") {
      // A distant spherical Gaussian (seed 004): amplitude e^(sharpness (axis.l - 1)).
      glm::dvec3 axis{0, 1, 0}, amplitude{1, 1, 1};
      double sharpness = 0;
      r.Keys({"type", "axis", "sharpness", "amplitude"})
          .Require("axis")
          .Require("sharpness")
          .Require("amplitude")
          .Vec3("axis", &axis)
          .Number("sharpness", &sharpness, 0, kMaxSgSharpness)
          .Vec3("amplitude", &amplitude);
      if (r.ok() && glm::length(axis) < 1e-9) r.FailKey("axis", "must not be zero");
      if (r.ok() && glm::any(glm::lessThan(amplitude, glm::dvec3(0)))) r.FailKey("amplitude", "must be >= 0");
      s.light.type = shading::LightType::kSg;
      if (r.ok()) s.light.vec = glm::normalize(axis);
      s.light.radius = sharpness;
      s.light.radiance = amplitude;
    } else if (r.ok()) {
      r.FailKey("type", "must be directional, sphere or sg, got '" + type + "'");
    }
    if (!r.ok()) return R::Failure(r.error());
  }
  if (j.contains("material")) {
    if (!j["material"].is_string()) return R::Failure(source + ": /material: must be a spec string like \"ggx:0.05\"");
    auto m = ParseMaterial(j["material"].get<std::string>(), s.material);
    if (!m) return R::Failure(source + ": /material: " + m.error());
    s.material = *m;
  }
  if (j.contains("camera")) {
    const auto& cj = j["camera"];
    if (!cj.is_object()) return R::Failure(source + ": /camera: must be an object");
    FieldReader r(cj, source, "/camera");
    r.Keys({"target", "distance", "elevation_deg", "azimuth_deg", "fov_y_deg"})
        .Vec3("target", &s.rig.target)
        .Number("distance", &s.rig.distance, 1e-6, kMaxCoordinate)
        .Number("elevation_deg", &s.rig.elevation_deg, -89, 89)
        .Number("azimuth_deg", &s.rig.azimuth_deg, -1e6, 1e6)
        .Number("fov_y_deg", &s.rig.fov_y_deg, 1, 170);
    if (!r.ok()) return R::Failure(r.error());
  }
  return s;
}

namespace {
// The whole of `text` as one finite number.
bool WholeFiniteNumber(const std::string& text, double* out) {
  std::size_t used = 0;
  try {
    *out = std::stod(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used != 0 && used == text.size() && std::isfinite(*out);
}
}  // namespace

Result<shading::MaterialDesc> ParseMaterial(std::string_view spec, const shading::MaterialDesc& base) {
  using R = Result<shading::MaterialDesc>;
  const std::string usage =
      " (expected NDF:ALPHA[,ALPHA_Y][,f0=V|R/G/B][,albedo=V|R/G/B], e.g. ggx:0.05, or blinn-phong:POWER[,POWER_Y], "
      "or glints:ALPHA[,ALPHA_Y][,local=ALPHA_L][,density=N])";
  shading::MaterialDesc m = base;
  auto colon = spec.find(':');
  if (colon == std::string_view::npos) return R::Failure("material '" + std::string(spec) + "'" + usage);
  auto ndf = shading::ParseNdf(spec.substr(0, colon));
  if (!ndf)
    return R::Failure("material '" + std::string(spec) + "': NDF must be ggx, beckmann, blinn-phong or glints" + usage);
  m.ndf = *ndf;
  const bool glints = m.ndf == shading::Ndf::kGlints;
  m.glint_alpha_l = glints ? kDefaultGlintAlphaL : 0.0;
  m.glint_density = glints ? kDefaultGlintDensity : 0.0;
  // Blinn-Phong is given by its power s (seed 003), alpha^2 = 2 / (s + 2).
  const bool power = m.ndf == shading::Ndf::kBlinnPhong;
  std::vector<double> alphas;
  std::stringstream ss{std::string(spec.substr(colon + 1))};
  std::string item;
  while (std::getline(ss, item, ',')) {
    auto eq = item.find('=');
    if (eq == std::string::npos) {
      double a = 0;
      const bool number = WholeFiniteNumber(item, &a);
      if (power) {
        if (!number || a < 0 || a > 1e8)
          return R::Failure("material '" + std::string(spec) + "': Blinn-Phong power '" + item +
                            "' must be a number in [0, 1e8]");
        a = shading::BlinnPhongAlpha(a);
      }
      if (!number || a <= 0 || a > 1)
        return R::Failure("material '" + std::string(spec) + "': roughness '" + item + "' must be a number in (0, 1]");
      if (alphas.size() == 2)
        return R::Failure("material '" + std::string(spec) + "': at most two roughness values" + usage);
      alphas.push_back(a);
      continue;
    }
    std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "local" || key == "density") {
      if (!glints)
        return R::Failure("material '" + std::string(spec) + "': '" + key + "' is a glint material's field (glints:...)");
      double v = 0;
      const bool ok = WholeFiniteNumber(value, &v) && (key == "local" ? v > 0 && v <= 1 : v > 0 && v <= kMaxGlintDensity);
      if (!ok)
        return R::Failure("material '" + std::string(spec) + "': " + key + " '" + value + "' must be a number in " +
                          (key == "local" ? "(0, 1]" : "(0, 1e12]"));
      (key == "local" ? m.glint_alpha_l : m.glint_density) = v;
      continue;
    }
    glm::dvec3 rgb;
    if (!ParseRgb(value, &rgb))
      return R::Failure("material '" + std::string(spec) + "': " + key + " expects V or R/G/B (>= 0), got '" + value +
                        "'");
    if (key == "f0") {
      if (glm::any(glm::greaterThan(rgb, glm::dvec3(1))))
        return R::Failure("material '" + std::string(spec) + "': f0 must be <= 1");
      m.f0 = rgb;
    } else if (key == "albedo") {
      m.albedo = rgb;
    } else {
      return R::Failure("material '" + std::string(spec) + "': unknown field '" + key + "'" + usage);
    }
  }
  if (alphas.empty()) return R::Failure("material '" + std::string(spec) + "': no roughness" + usage);
  m.alpha = {alphas[0], alphas.size() > 1 ? alphas[1] : alphas[0]};
  return m;
}

std::string MaterialSpec(const shading::MaterialDesc& m) {
  auto rgb = [](glm::dvec3 c) {
    std::ostringstream o;
    o.precision(6);
    if (c.x == c.y && c.y == c.z)
      o << c.x;
    else
      o << c.x << "/" << c.y << "/" << c.z;
    return o.str();
  };
  std::ostringstream o;
  o.precision(6);
  auto value = [&m](double alpha) { return m.ndf == shading::Ndf::kBlinnPhong ? shading::BlinnPhongPower(alpha) : alpha; };
  o << shading::NdfName(m.ndf) << ":" << value(m.alpha.x);
  if (m.alpha.y != m.alpha.x) o << "," << value(m.alpha.y);
  if (m.ndf == shading::Ndf::kGlints) o << ",local=" << m.glint_alpha_l << ",density=" << m.glint_density;
  o << ",f0=" << rgb(m.f0) << ",albedo=" << rgb(m.albedo);
  return o.str();
}

int SceneFeatures(const Scene& scene) {
  using namespace shading;
  int mask = 0;
  for (const Primitive& p : scene.primitives) {
    if (p.normal_map) mask |= kSceneNormalMaps;
    if (p.type == Primitive::Type::kSphere) mask |= kSceneSpheres;
    if (p.type == Primitive::Type::kCapsule) mask |= kSceneCapsules;
    if (p.type == Primitive::Type::kPlane) mask |= kScenePlanes | (p.bump_slope != 0 ? kSceneBumps : 0);
  }
  return mask;
}

std::vector<glm::vec4> PackScene(const Scene& scene) {
  std::vector<Primitive> bounded, unbounded;
  for (const Primitive& p : scene.primitives) (p.type == Primitive::Type::kPlane ? unbounded : bounded).push_back(p);
  std::vector<int> order(bounded.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<BvhNode> nodes;
  if (!bounded.empty()) BuildNode(nodes, order, 0, static_cast<int>(bounded.size()), bounded);
  const int first_prim_word = 1 + 2 * static_cast<int>(nodes.size());
  std::vector<glm::vec4> words;
  words.push_back({float(bounded.size()), float(nodes.size()), float(first_prim_word), float(unbounded.size())});
  for (const BvhNode& n : nodes) {
    words.push_back({float(n.box.lo.x), float(n.box.lo.y), float(n.box.lo.z), float(n.skip)});
    words.push_back({float(n.box.hi.x), float(n.box.hi.y), float(n.box.hi.z), float(n.prim + 1)});  // 0: interior
  }
  std::vector<const Primitive*> packed;
  for (int i : order) packed.push_back(&bounded[i]);
  for (const Primitive& p : unbounded) packed.push_back(&p);
  // Normal maps (normal_map.glsl's layout): one header per mapped primitive
  // (its scale is its own), then each map's texels once however many
  // primitives share it.
  std::vector<const NormalMap*> maps;
  std::vector<int> header_word(packed.size(), 0);
  int next = first_prim_word + 3 * static_cast<int>(packed.size());
  for (std::size_t k = 0; k < packed.size(); ++k) {
    const NormalMap* map = packed[k]->normal_map.get();
    if (!map) continue;
    header_word[k] = next;
    next += 2 + static_cast<int>(map->levels.size());
    if (std::find(maps.begin(), maps.end(), map) == maps.end()) maps.push_back(map);
  }
  std::vector<std::vector<int>> level_word(maps.size());
  for (std::size_t m = 0; m < maps.size(); ++m)
    for (const NormalMapLevel& level : maps[m]->levels) {
      level_word[m].push_back(next);
      next += 3 * static_cast<int>(level.texels.size());
    }
  for (std::size_t k = 0; k < packed.size(); ++k) {
    const Primitive& p = *packed[k];
    words.push_back(PrimWord0(p));
    words.push_back({float(p.a.x), float(p.a.y), float(p.a.z), float(header_word[k])});
    words.push_back({float(p.b.x), float(p.b.y), float(p.b.z), 0.0f});
  }
  for (std::size_t k = 0; k < packed.size(); ++k) {
    const NormalMap* map = packed[k]->normal_map.get();
    if (!map) continue;
    const std::size_t m = std::size_t(std::find(maps.begin(), maps.end(), map) - maps.begin());
    const NormalMapLevel& top = map->levels.front();
    words.push_back({float(map->levels.size()), float(top.width), float(top.height), 0.0f});
    const glm::dvec2 scale = packed[k]->normal_map_scale;
    words.push_back({float(scale.x), float(scale.y), 0.0f, 0.0f});
    for (std::size_t l = 0; l < map->levels.size(); ++l)
      words.push_back({float(level_word[m][l]), float(map->levels[l].width), float(map->levels[l].height), 0.0f});
  }
  for (const NormalMap* map : maps)
    for (const NormalMapLevel& level : map->levels)
      for (const NormalMapTexel& t : level.texels) {
        words.push_back({t.mean_normal.x, t.mean_normal.y, t.mean_normal.z, t.toksvig_ft});
        words.push_back({t.b.x, t.b.y, t.m.x, t.m.y});
        words.push_back({t.m.z, 0.0f, 0.0f, 0.0f});
      }
  return words;
}

// --- camera paths -------------------------------------------------------------

namespace {
constexpr std::pair<CameraPath, std::string_view> kCameraPaths[] = {{CameraPath::kOrbit, "orbit"},
                                                                    {CameraPath::kPan, "pan"},
                                                                    {CameraPath::kDolly, "dolly"},
                                                                    {CameraPath::kVrJitter, "vr-jitter"},
                                                                    {CameraPath::kStatic, "static"}};
}  // namespace

std::vector<std::string_view> CameraPathNames() {
  std::vector<std::string_view> names;
  for (const auto& [path, name] : kCameraPaths) names.push_back(name);
  return names;
}

std::optional<CameraPath> ParseCameraPath(std::string_view name) {
  for (const auto& [path, n] : kCameraPaths)
    if (n == name) return path;
  return std::nullopt;
}

std::string_view CameraPathName(CameraPath path) {
  for (const auto& [p, name] : kCameraPaths)
    if (p == path) return name;
  return "static";
}

namespace {
shading::CameraDesc LookAt(glm::dvec3 pos, glm::dvec3 target, double fov_y_deg, int width, int height) {
  shading::CameraDesc c;
  c.pos = pos;
  c.fwd = glm::normalize(target - pos);
  glm::dvec3 up_hint{0, 1, 0};
  if (std::abs(glm::dot(c.fwd, up_hint)) > 0.999) up_hint = {0, 0, -1};
  c.right = glm::normalize(glm::cross(c.fwd, up_hint));
  c.up = glm::cross(c.right, c.fwd);
  c.tan_half_fov_y = std::tan(fov_y_deg * kPi / 360.0);
  c.width = width;
  c.height = height;
  return c;
}

glm::dvec3 Spherical(double distance, double elevation_deg, double azimuth_deg) {
  double el = elevation_deg * kPi / 180, az = azimuth_deg * kPi / 180;
  return distance * glm::dvec3(std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el));
}
}  // namespace

// orbit: 45 degrees per second around the target. pan: sideways at 0.1
// distance per second, looking in a fixed direction. dolly: the distance
// halves every 2 seconds (the footprint scale changes). vr-jitter: head-tracking
// tremor, sums of sines of ~0.3% of the distance and ~0.2 degrees of rotation.
shading::CameraDesc CameraAt(CameraPath path, const CameraRig& rig, int frame, double fps, int width, int height) {
  const double t = frame / fps;
  glm::dvec3 pos = rig.target + Spherical(rig.distance, rig.elevation_deg, rig.azimuth_deg);
  switch (path) {
    case CameraPath::kOrbit: {
      pos = rig.target + Spherical(rig.distance, rig.elevation_deg, rig.azimuth_deg + 45.0 * t);
      return LookAt(pos, rig.target, rig.fov_y_deg, width, height);
    }
    case CameraPath::kPan: {
      shading::CameraDesc c0 = LookAt(pos, rig.target, rig.fov_y_deg, width, height);
      glm::dvec3 shift = c0.right * (0.1 * rig.distance * t);
      return LookAt(pos + shift, rig.target + shift, rig.fov_y_deg, width, height);
    }
    case CameraPath::kDolly: {
      pos = rig.target + Spherical(rig.distance * std::exp2(-t / 2.0), rig.elevation_deg, rig.azimuth_deg);
      return LookAt(pos, rig.target, rig.fov_y_deg, width, height);
    }
    case CameraPath::kVrJitter: {
      const double a = 0.003 * rig.distance, w = 2 * kPi;
      glm::dvec3 d{std::sin(w * 0.7 * t) + 0.5 * std::sin(w * 2.9 * t + 1.0),
                   std::sin(w * 1.3 * t + 2.0) + 0.4 * std::sin(w * 3.7 * t), std::sin(w * 0.9 * t + 0.5)};
      double yaw = 0.2 * std::sin(w * 0.5 * t + 0.3), pitch = 0.15 * std::sin(w * 1.1 * t + 1.2);
      shading::CameraDesc c0 = LookAt(pos, rig.target, rig.fov_y_deg, width, height);
      glm::dvec3 look = c0.fwd + c0.right * std::tan(yaw * kPi / 180) + c0.up * std::tan(pitch * kPi / 180);
      glm::dvec3 p = pos + a * d;
      return LookAt(p, p + look, rig.fov_y_deg, width, height);
    }
    case CameraPath::kStatic: break;
  }
  return LookAt(pos, rig.target, rig.fov_y_deg, width, height);
}

}  // namespace shimmer::scene
