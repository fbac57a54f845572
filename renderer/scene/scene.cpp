#include "scene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

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

Scene SphereScene() {
  Scene s;
  s.name = "sphere";
  s.primitives.push_back({Primitive::Type::kSphere, {0, 0, 0}, {0, 0, 0}, 1.0});
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
      s.primitives.push_back({Primitive::Type::kSphere, {x, r, z}, {0, 0, 0}, r});
    }
  s.primitives.push_back({Primitive::Type::kPlane, {0, 0, 0}, {0, 0, 0}, 0.0});
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
    s.primitives.push_back({Primitive::Type::kCapsule, c - d, c + d, r});
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

template <class T>
Parsed<T> Fail(std::string message) {
  Parsed<T> p;
  p.error = std::move(message);
  return p;
}

bool ReadVec3(const nlohmann::json& j, const char* key, glm::dvec3* out, std::string* error, const std::string& where) {
  if (!j.contains(key)) return true;
  const auto& v = j[key];
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number()) {
    *error = where + ": '" + key + "' must be an array of 3 numbers";
    return false;
  }
  *out = {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
  return true;
}

bool ReadNumber(const nlohmann::json& j, const char* key, double* out, std::string* error, const std::string& where,
                double min_value) {
  if (!j.contains(key)) return true;
  if (!j[key].is_number() || !std::isfinite(j[key].get<double>()) || j[key].get<double>() < min_value) {
    *error = where + ": '" + key + "' must be a finite number >= " + std::to_string(min_value);
    return false;
  }
  *out = j[key].get<double>();
  return true;
}

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
  if (v.size() == 1) *out = glm::dvec3(v[0]);
  else if (v.size() == 3) *out = {v[0], v[1], v[2]};
  else return false;
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
  int skip = 0;    // the node after this subtree
  int prim = -1;   // a leaf's one primitive; -1: interior
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

}  // namespace

std::vector<std::string_view> BuiltinSceneNames() { return {"sphere", "sphere-field", "wires", "bumpy-plane"}; }

Parsed<Scene> LoadScene(const std::string& name) {
  Parsed<Scene> p;
  if (name == "sphere") p.value = SphereScene();
  else if (name == "sphere-field") p.value = SphereFieldScene();
  else if (name == "wires") p.value = WiresScene();
  else if (name == "bumpy-plane") p.value = BumpyPlaneScene();
  else {
    std::ifstream in(name);
    if (!in) {
      std::string list;
      for (auto n : BuiltinSceneNames()) list += (list.empty() ? "" : ", ") + std::string(n);
      return Fail<Scene>("unknown scene '" + name + "': not a built-in scene (" + list + ") nor a readable JSON file");
    }
    std::stringstream ss;
    ss << in.rdbuf();
    return ParseSceneJson(ss.str(), name);
  }
  return p;
}

Parsed<Scene> ParseSceneJson(std::string_view text, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    return Fail<Scene>(source + ": not valid JSON: " + e.what());
  }
  if (!j.is_object()) return Fail<Scene>(source + ": a scene is a JSON object");
  Scene s;
  s.name = j.value("name", source);
  std::string error;
  if (!j.contains("primitives") || !j["primitives"].is_array() || j["primitives"].empty())
    return Fail<Scene>(source + ": 'primitives' must be a non-empty array");
  int index = 0;
  for (const auto& pj : j["primitives"]) {
    std::string where = source + ": primitives[" + std::to_string(index++) + "]";
    if (!pj.is_object() || !pj.contains("type") || !pj["type"].is_string())
      return Fail<Scene>(where + ": needs a 'type' (sphere, capsule, plane)");
    std::string type = pj["type"];
    Primitive p;
    if (type == "sphere") {
      p.type = Primitive::Type::kSphere;
      if (!ReadVec3(pj, "center", &p.a, &error, where) || !ReadNumber(pj, "radius", &p.radius, &error, where, 1e-9))
        return Fail<Scene>(error);
    } else if (type == "capsule") {
      p.type = Primitive::Type::kCapsule;
      p.radius = 0.02;
      if (!pj.contains("a") || !pj.contains("b")) return Fail<Scene>(where + ": a capsule needs ends 'a' and 'b'");
      if (!ReadVec3(pj, "a", &p.a, &error, where) || !ReadVec3(pj, "b", &p.b, &error, where) ||
          !ReadNumber(pj, "radius", &p.radius, &error, where, 1e-9))
        return Fail<Scene>(error);
      if (glm::length(p.b - p.a) < 1e-9) return Fail<Scene>(where + ": capsule ends 'a' and 'b' coincide");
    } else if (type == "plane") {
      p.type = Primitive::Type::kPlane;
      p.radius = 0;
      if (!ReadNumber(pj, "height", &p.radius, &error, where, -1e30) ||
          !ReadNumber(pj, "bump_slope", &p.bump_slope, &error, where, 0) ||
          !ReadNumber(pj, "bump_frequency", &p.bump_frequency, &error, where, 0))
        return Fail<Scene>(error);
      if (p.bump_slope > 0 && p.bump_frequency <= 0)
        return Fail<Scene>(where + ": 'bump_slope' needs a positive 'bump_frequency'");
    } else {
      return Fail<Scene>(where + ": unknown type '" + type + "' (sphere, capsule, plane)");
    }
    s.primitives.push_back(p);
  }
  if (j.contains("light")) {
    const auto& lj = j["light"];
    std::string where = source + ": light";
    std::string type = lj.is_object() ? lj.value("type", "directional") : "";
    if (type == "directional") {
      glm::dvec3 dir{0, 1, 0}, rad{1, 1, 1};
      if (!ReadVec3(lj, "direction", &dir, &error, where) || !ReadVec3(lj, "irradiance", &rad, &error, where))
        return Fail<Scene>(error);
      if (glm::length(dir) < 1e-9) return Fail<Scene>(where + ": 'direction' must not be zero");
      s.light.type = shading::LightType::kDirectional;
      s.light.vec = glm::normalize(dir);
      s.light.radiance = rad;
    } else if (type == "sphere") {
      s.light.type = shading::LightType::kSphere;
      s.light.radius = 0.05;
      if (!ReadVec3(lj, "center", &s.light.vec, &error, where) ||
          !ReadVec3(lj, "intensity", &s.light.radiance, &error, where) ||
          !ReadNumber(lj, "radius", &s.light.radius, &error, where, 1e-6))
        return Fail<Scene>(error);
    } else {
      return Fail<Scene>(where + ": 'type' must be directional or sphere");
    }
  }
  if (j.contains("material")) {
    if (!j["material"].is_string()) return Fail<Scene>(source + ": 'material' must be a spec string like \"ggx:0.05\"");
    auto m = ParseMaterial(j["material"].get<std::string>(), s.material);
    if (!m.ok()) return Fail<Scene>(source + ": material: " + m.error);
    s.material = m.value;
  }
  if (j.contains("camera")) {
    const auto& cj = j["camera"];
    std::string where = source + ": camera";
    if (!ReadVec3(cj, "target", &s.rig.target, &error, where) ||
        !ReadNumber(cj, "distance", &s.rig.distance, &error, where, 1e-6) ||
        !ReadNumber(cj, "elevation_deg", &s.rig.elevation_deg, &error, where, -89) ||
        !ReadNumber(cj, "azimuth_deg", &s.rig.azimuth_deg, &error, where, -1e6) ||
        !ReadNumber(cj, "fov_y_deg", &s.rig.fov_y_deg, &error, where, 1))
      return Fail<Scene>(error);
    if (s.rig.elevation_deg > 89 || s.rig.fov_y_deg > 170)
      return Fail<Scene>(where + ": elevation_deg must be <= 89 and fov_y_deg <= 170");
  }
  Parsed<Scene> p;
  p.value = std::move(s);
  return p;
}

Parsed<shading::MaterialDesc> ParseMaterial(std::string_view spec, const shading::MaterialDesc& base) {
  using R = Parsed<shading::MaterialDesc>;
  const std::string usage = " (expected NDF:ALPHA[,ALPHA_Y][,f0=V|R/G/B][,albedo=V|R/G/B], e.g. ggx:0.05)";
  shading::MaterialDesc m = base;
  auto colon = spec.find(':');
  if (colon == std::string_view::npos) return Fail<shading::MaterialDesc>("material '" + std::string(spec) + "'" + usage);
  auto ndf = shading::ParseNdf(spec.substr(0, colon));
  if (!ndf)
    return Fail<shading::MaterialDesc>("material '" + std::string(spec) + "': NDF must be ggx or beckmann" + usage);
  m.ndf = *ndf;
  std::vector<double> alphas;
  std::stringstream ss{std::string(spec.substr(colon + 1))};
  std::string item;
  while (std::getline(ss, item, ',')) {
    auto eq = item.find('=');
    if (eq == std::string::npos) {
      std::size_t used = 0;
      double a = 0;
      try {
        a = std::stod(item, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != item.size() || !std::isfinite(a) || a <= 0 || a > 1)
        return Fail<shading::MaterialDesc>("material '" + std::string(spec) + "': roughness '" + item +
                                           "' must be a number in (0, 1]");
      if (alphas.size() == 2) return Fail<shading::MaterialDesc>("material '" + std::string(spec) + "': at most two roughness values" + usage);
      alphas.push_back(a);
      continue;
    }
    std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    glm::dvec3 rgb;
    if (!ParseRgb(value, &rgb))
      return Fail<shading::MaterialDesc>("material '" + std::string(spec) + "': " + key + " expects V or R/G/B (>= 0), got '" + value + "'");
    if (key == "f0") {
      if (glm::any(glm::greaterThan(rgb, glm::dvec3(1))))
        return Fail<shading::MaterialDesc>("material '" + std::string(spec) + "': f0 must be <= 1");
      m.f0 = rgb;
    } else if (key == "albedo") {
      m.albedo = rgb;
    } else {
      return Fail<shading::MaterialDesc>("material '" + std::string(spec) + "': unknown field '" + key + "'" + usage);
    }
  }
  if (alphas.empty()) return Fail<shading::MaterialDesc>("material '" + std::string(spec) + "': no roughness" + usage);
  m.alpha = {alphas[0], alphas.size() > 1 ? alphas[1] : alphas[0]};
  R r;
  r.value = m;
  return r;
}

std::string MaterialSpec(const shading::MaterialDesc& m) {
  auto rgb = [](glm::dvec3 c) {
    std::ostringstream o;
    o.precision(6);
    if (c.x == c.y && c.y == c.z) o << c.x;
    else o << c.x << "/" << c.y << "/" << c.z;
    return o.str();
  };
  std::ostringstream o;
  o.precision(6);
  o << shading::NdfName(m.ndf) << ":" << m.alpha.x;
  if (m.alpha.y != m.alpha.x) o << "," << m.alpha.y;
  o << ",f0=" << rgb(m.f0) << ",albedo=" << rgb(m.albedo);
  return o.str();
}

int SceneFeatures(const Scene& scene) {
  using namespace shading;
  int mask = 0;
  for (const Primitive& p : scene.primitives) {
    if (p.type == Primitive::Type::kSphere) mask |= kSceneSpheres;
    if (p.type == Primitive::Type::kCapsule) mask |= kSceneCapsules;
    if (p.type == Primitive::Type::kPlane) mask |= kScenePlanes | (p.bump_slope != 0 ? kSceneBumps : 0);
  }
  return mask;
}

std::vector<glm::vec4> PackScene(const Scene& scene) {
  std::vector<Primitive> bounded, unbounded;
  for (const Primitive& p : scene.primitives)
    (p.type == Primitive::Type::kPlane ? unbounded : bounded).push_back(p);
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
  auto push = [&words](const Primitive& p) {
    words.push_back(PrimWord0(p));
    words.push_back({float(p.a.x), float(p.a.y), float(p.a.z), 0.0f});
    words.push_back({float(p.b.x), float(p.b.y), float(p.b.z), 0.0f});
  };
  for (int i : order) push(bounded[i]);
  for (const Primitive& p : unbounded) push(p);
  return words;
}

// --- camera paths -------------------------------------------------------------

std::vector<std::string_view> CameraPathNames() { return {"orbit", "pan", "dolly", "vr-jitter", "static"}; }

bool IsCameraPath(std::string_view name) {
  for (auto n : CameraPathNames())
    if (n == name) return true;
  return false;
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
shading::CameraDesc CameraAt(std::string_view path, const CameraRig& rig, int frame, double fps, int width,
                             int height) {
  const double t = frame / fps;
  glm::dvec3 pos = rig.target + Spherical(rig.distance, rig.elevation_deg, rig.azimuth_deg);
  if (path == "orbit") {
    pos = rig.target + Spherical(rig.distance, rig.elevation_deg, rig.azimuth_deg + 45.0 * t);
    return LookAt(pos, rig.target, rig.fov_y_deg, width, height);
  }
  if (path == "pan") {
    shading::CameraDesc c0 = LookAt(pos, rig.target, rig.fov_y_deg, width, height);
    glm::dvec3 shift = c0.right * (0.1 * rig.distance * t);
    return LookAt(pos + shift, rig.target + shift, rig.fov_y_deg, width, height);
  }
  if (path == "dolly") {
    pos = rig.target + Spherical(rig.distance * std::exp2(-t / 2.0), rig.elevation_deg, rig.azimuth_deg);
    return LookAt(pos, rig.target, rig.fov_y_deg, width, height);
  }
  if (path == "vr-jitter") {
    const double a = 0.003 * rig.distance, w = 2 * kPi;
    glm::dvec3 d{std::sin(w * 0.7 * t) + 0.5 * std::sin(w * 2.9 * t + 1.0),
                 std::sin(w * 1.3 * t + 2.0) + 0.4 * std::sin(w * 3.7 * t),
                 std::sin(w * 0.9 * t + 0.5)};
    double yaw = 0.2 * std::sin(w * 0.5 * t + 0.3), pitch = 0.15 * std::sin(w * 1.1 * t + 1.2);
    shading::CameraDesc c0 = LookAt(pos, rig.target, rig.fov_y_deg, width, height);
    glm::dvec3 look = c0.fwd + c0.right * std::tan(yaw * kPi / 180) + c0.up * std::tan(pitch * kPi / 180);
    glm::dvec3 p = pos + a * d;
    return LookAt(p, p + look, rig.fov_y_deg, width, height);
  }
  return LookAt(pos, rig.target, rig.fov_y_deg, width, height);  // static
}

}  // namespace shimmer::scene
