// The built-in scenes: small analytic shots (spheres, wires, bumpy and
// normal-mapped planes, SG-lit and glint scenes) with their lights and camera
// rigs, and LoadScene, which finds a built-in, SCENE@MAP or a JSON file.
#include "shimmer/renderer/scene.h"

#include <cmath>
#include <filesystem>

#include "shimmer/core/json_file.h"

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

}  // namespace shimmer::scene
