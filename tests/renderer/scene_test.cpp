// Scenes, material specs, camera paths and the packed scene (CPU only).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "shimmer/renderer/scene.h"

namespace shimmer::scene {
namespace {

TEST(Material, ParsesIsotropicAnisotropicAndColours) {
  shading::MaterialDesc base;
  auto m = ParseMaterial("ggx:0.05", base);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->ndf, shading::Ndf::kGgx);
  EXPECT_DOUBLE_EQ(m->alpha.x, 0.05);
  EXPECT_DOUBLE_EQ(m->alpha.y, 0.05);
  auto a = ParseMaterial("beckmann:0.02,0.1,f0=0.9/0.6/0.3,albedo=0", base);
  ASSERT_TRUE(a.ok()) << a.error();
  EXPECT_EQ(a->ndf, shading::Ndf::kBeckmann);
  EXPECT_DOUBLE_EQ(a->alpha.y, 0.1);
  EXPECT_DOUBLE_EQ(a->f0.y, 0.6);
  EXPECT_DOUBLE_EQ(a->albedo.z, 0.0);
  auto round_trip = ParseMaterial(MaterialSpec(a.value()), base);
  ASSERT_TRUE(round_trip.ok()) << round_trip.error();
  EXPECT_DOUBLE_EQ(round_trip->f0.x, 0.9);
}

TEST(Material, RejectsBadSpecsWithAMessage) {
  shading::MaterialDesc base;
  for (const char* bad : {"ggx", "phong:0.1", "ggx:0", "ggx:1.5", "ggx:abc", "ggx:0.1,0.2,0.3", "ggx:0.1,f0=2",
                          "ggx:0.1,gloss=1", "ggx:0.1,albedo=1/2", "ggx:"}) {
    auto m = ParseMaterial(bad, base);
    EXPECT_FALSE(m.ok()) << bad;
    EXPECT_NE(m.error().find("material"), std::string::npos) << m.error();
  }
}

// Glint materials (docs/glints.md): D_m's alpha, the local lobe and the
// density, with defaults, a round trip through MaterialSpec, and the glint
// fields refused elsewhere or out of range.
TEST(Material, ParsesGlintMaterials) {
  shading::MaterialDesc base;
  auto d = ParseMaterial("glints:0.3", base);
  ASSERT_TRUE(d.ok()) << d.error();
  EXPECT_EQ(d->ndf, shading::Ndf::kGlints);
  EXPECT_DOUBLE_EQ(d->glint_alpha_l, 0.03);
  EXPECT_DOUBLE_EQ(d->glint_density, 1e4);
  auto m = ParseMaterial("glints:0.2,0.4,local=0.05,density=2.5e5,albedo=0.1", base);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_DOUBLE_EQ(m->alpha.y, 0.4);
  EXPECT_DOUBLE_EQ(m->glint_alpha_l, 0.05);
  EXPECT_DOUBLE_EQ(m->glint_density, 2.5e5);
  auto round_trip = ParseMaterial(MaterialSpec(*m), base);
  ASSERT_TRUE(round_trip.ok()) << round_trip.error();
  EXPECT_DOUBLE_EQ(round_trip->glint_density, 2.5e5);
  EXPECT_DOUBLE_EQ(round_trip->glint_alpha_l, 0.05);
  auto smooth = ParseMaterial("ggx:0.1,density=5", base);
  ASSERT_FALSE(smooth.ok());
  EXPECT_NE(smooth.error().find("glint material's field"), std::string::npos) << smooth.error();
  for (const char* bad : {"glints:0.3,local=0", "glints:0.3,local=2", "glints:0.3,density=-1", "glints:0.3,density=x",
                          "glints:0.3,density=1e13"}) {
    auto r = ParseMaterial(bad, base);
    EXPECT_FALSE(r.ok()) << bad;
    EXPECT_NE(r.error().find("must be a number in"), std::string::npos) << r.error();
  }
}

TEST(SceneJson, LoadsPrimitivesLightMaterialCamera) {
  auto s = ParseSceneJson(R"({"name": "two", "primitives": [
      {"type": "sphere", "center": [0, 1, 0], "radius": 0.5},
      {"type": "capsule", "a": [0, 0, 0], "b": [1, 0, 0], "radius": 0.01},
      {"type": "plane", "height": -1, "bump_slope": 0.1, "bump_frequency": 5}],
    "light": {"type": "sphere", "center": [0, 5, 0], "intensity": [10, 10, 10], "radius": 0.1},
    "material": "beckmann:0.2", "camera": {"distance": 7, "fov_y_deg": 20}})",
                          "test.json");
  ASSERT_TRUE(s.ok()) << s.error();
  EXPECT_EQ(s->name, "two");
  ASSERT_EQ(s->primitives.size(), 3u);
  EXPECT_EQ(s->primitives[1].type, Primitive::Type::kCapsule);
  EXPECT_EQ(s->light.type, shading::LightType::kSphere);
  EXPECT_EQ(s->material.ndf, shading::Ndf::kBeckmann);
  EXPECT_DOUBLE_EQ(s->rig.distance, 7);
  EXPECT_FALSE(s->light.shadows);
  EXPECT_EQ(SceneFeatures(*s) & shading::kSceneShadows, 0);
}

// A light casts shadows where the scene asks; only then does the kernel
// trace shadow rays (its feature mask says so).
TEST(SceneJson, ALightCastsShadowsWhereTheSceneAsks) {
  for (const char* light : {R"({"direction": [0, 1, 0], "shadows": true})",
                            R"({"type": "sphere", "center": [0, 5, 0], "intensity": [9, 9, 9], "shadows": true})"}) {
    auto s = ParseSceneJson(std::string(R"({"primitives": [{"type": "plane"}], "light": )") + light + "}", "s.json");
    ASSERT_TRUE(s.ok()) << s.error();
    EXPECT_TRUE(s->light.shadows) << light;
    EXPECT_NE(SceneFeatures(*s) & shading::kSceneShadows, 0) << light;
  }
}

// Each malformed file gets one message that names the file and the JSON
// Pointer (RFC 6901) of the key at fault, then the problem: exactly the
// expected text up to where the problem's details start.
TEST(SceneJson, EveryErrorNamesTheFileAndTheJsonPointerOfTheKey) {
  struct Case {
    const char* json;
    const char* expect;  // after "bad.json: "
  };
  const std::string sphere = R"({"type": "sphere", "center": [0,0,0]})";
  const std::vector<Case> cases = {
      {"[1, 2]", "/: a scene is a JSON object"},
      {"{}", "/primitives: is required"},
      {R"({"primitives": []})", "/primitives: must be a non-empty array"},
      {R"({"primitives": {"type": "sphere"}})", "/primitives: must be a non-empty array"},
      {R"({"primitives": [3]})", "/primitives/0: must be an object with a 'type'"},
      {R"({"primitives": [{"type": "plane", "normal_map": 1}]})", "/primitives/0/normal_map: must be an object"},
      {R"({"primitives": [{"type": "plane", "normal_map": {}}]})",
       "/primitives/0/normal_map: needs exactly one of 'file' and 'procedural'"},
      {R"({"primitives": [{"type": "plane", "normal_map": {"procedural": "nope"}}]})",
       "/primitives/0/normal_map: "},
      {R"({"primitives": [{"type": "plane", "normal_map": {"procedural": "bumps", "scale": [1]}}]})",
       "/primitives/0/normal_map/scale: must be an array of 2 numbers"},
      {R"({"primitives": [{"type": "plane", "normal_map": {"procedural": "bumps", "strength": 11}}]})",
       "/primitives/0/normal_map/strength: must be a number in [0, 10]"},
      {R"({"primitives": [{"type": "plane", "normal_map": {"procedural": "bumps", "tiling": 2}}]})",
       "/primitives/0/normal_map/tiling: unknown key"},
      {R"({"primitives": [{"type": "sphere", "center": [0,0,0], "normal_map": {"file": "missing.png"}}]})",
       "/primitives/0/normal_map: "},
      {R"({"primitives": [{"type": "plane", "bump_slope": 0.1, "bump_frequency": 3,
                           "normal_map": {"procedural": "bumps"}}]})",
       "/primitives/0/normal_map: a plane with 'bump_slope'"},
      {R"({"primitives": [{"center": [0,0,0]}]})", "/primitives/0/type: is required"},
      {R"({"primitives": [{"type": 7}]})", "/primitives/0/type: must be a string"},
      {R"({"primitives": [SPHERE, {"type": "cube"}]})", "/primitives/1/type: unknown type 'cube'"},
      {R"({"primitives": [{"type": "sphere", "radius": 1}]})", "/primitives/0/center: is required"},
      {R"({"primitives": [{"type": "sphere", "center": [0, 0]}]})", "/primitives/0/center: must be an array of 3"},
      {R"({"primitives": [{"type": "sphere", "center": [1e300, 0, 0]}]})", "/primitives/0/center: must be finite"},
      {R"({"primitives": [{"type": "sphere", "center": [0,0,0], "radius": -1}]})",
       "/primitives/0/radius: must be a number > 0"},
      {R"({"primitives": [{"type": "sphere", "center": [0,0,0], "radius": "big"}]})",
       "/primitives/0/radius: must be a number"},
      {R"({"primitives": [{"type": "sphere", "center": [0,0,0], "radus": 1}]})",
       "/primitives/0/radus: unknown key (expected: type, center, radius, normal_map)"},
      {R"({"primitives": [SPHERE, SPHERE, {"type": "capsule", "a": [0,0,0], "b": [0,0,0]}]})",
       "/primitives/2/b: coincides with 'a'"},
      {R"({"primitives": [{"type": "capsule", "a": [0,0,0]}]})", "/primitives/0/b: is required"},
      {R"({"primitives": [{"type": "plane", "bump_slope": 0.1}]})",
       "/primitives/0/bump_frequency: must be > 0 when 'bump_slope' is"},
      {R"({"primitives": [{"type": "plane", "height": null}]})", "/primitives/0/height: must be a number"},
      {R"({"name": 5, "primitives": [SPHERE]})", "/name: must be a string"},
      {R"({"primitives": [SPHERE], "lights": {}})", "/lights: unknown key"},
      {R"({"primitives": [SPHERE], "a/b~c": 1})", "/a~1b~0c: unknown key"},
      {R"({"primitives": [SPHERE], "light": [1]})", "/light: must be an object"},
      {R"({"primitives": [SPHERE], "light": {"type": 3}})", "/light/type: must be a string"},
      {R"({"primitives": [SPHERE], "light": {"type": "area"}})", "/light/type: must be directional, sphere or sg"},
      {R"({"primitives": [SPHERE], "light": {"direction": [0, 0, 0]}})", "/light/direction: must not be zero"},
      {R"({"primitives": [SPHERE], "light": {"irradiance": [1, -1, 1]}})", "/light/irradiance: must be >= 0"},
      {R"({"primitives": [SPHERE], "light": {"type": "sphere", "intensity": [1, 1, 1], "radius": 0}})",
       "/light/radius: must be a number in [1e-06, 1e+06]"},
      {R"({"primitives": [SPHERE], "light": {"type": "sg", "axis": [0, 1, 0], "amplitude": [1, 1, 1]}})",
       "/light/sharpness: is required"},
      {R"({"primitives": [SPHERE], "light": {"shadows": 1}})", "/light/shadows: must be true or false"},
      {R"({"primitives": [SPHERE], "light": {"type": "sg", "axis": [0, 1, 0], "sharpness": 5, "amplitude": [1, 1, 1],
                                              "shadows": true}})",
       "/light/shadows: an SG light is a distant lobe"},
      {R"({"primitives": [SPHERE], "material": 0.05})", "/material: must be a spec string"},
      {R"({"primitives": [SPHERE], "material": "ggx:7"})", "/material: material 'ggx:7'"},
      {R"({"primitives": [SPHERE], "camera": "far"})", "/camera: must be an object"},
      {R"({"primitives": [SPHERE], "camera": {"fov_y_deg": 180}})", "/camera/fov_y_deg: must be a number in [1, 170]"},
      {R"({"primitives": [SPHERE], "camera": {"zoom": 2}})", "/camera/zoom: unknown key"},
  };
  ASSERT_GE(cases.size(), 15u);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("scene_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / "bad.json";
  for (const Case& c : cases) {
    std::string json = c.json;
    for (size_t at; (at = json.find("SPHERE")) != std::string::npos;) json.replace(at, 6, sphere);
    std::ofstream(file) << json;
    auto s = LoadScene(file.string());
    ASSERT_FALSE(s.ok()) << json;
    const std::string expect = file.string() + ": " + c.expect;
    EXPECT_EQ(s.error().rfind(expect, 0), 0u) << json << "\n  got:    " << s.error() << "\n  wanted: " << expect;
    EXPECT_EQ(s.error().find('\n'), std::string::npos) << s.error();  // one line
  }
  std::filesystem::remove_all(dir);
}

// Syntax errors come from the JSON parser, with the line.
TEST(SceneJson, ASyntaxErrorNamesTheFileAndLine) {
  for (const char* json : {"{", R"({"primitives": [{"type": "sphere", "center": [0,0,1e999]}]})"}) {
    auto s = ParseSceneJson(json, "bad.json");
    ASSERT_FALSE(s.ok()) << json;
    EXPECT_EQ(s.error().rfind("bad.json:1:", 0), 0u) << s.error();
  }
}

TEST(SceneLoad, BuiltinsAndUnknownNames) {
  for (auto name : BuiltinSceneNames()) {
    auto s = LoadScene(std::string(name));
    ASSERT_TRUE(s.ok()) << name << ": " << s.error();
    EXPECT_FALSE(s->primitives.empty());
  }
  auto bad = LoadScene("no-such-scene");
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("unknown scene 'no-such-scene'"), std::string::npos) << bad.error();
}

// "SCENE@MAP": the scene with its maps replaced, everything else kept.
TEST(SceneLoad, AMapSuffixReplacesTheScenesNormalMaps) {
  auto base = LoadScene("nm-plane");
  auto ridged = LoadScene("nm-plane@ridges");
  ASSERT_TRUE(base.ok() && ridged.ok()) << ridged.error();
  EXPECT_EQ(ridged->name, "nm-plane@ridges");
  ASSERT_EQ(ridged->primitives.size(), base->primitives.size());
  const Primitive& p = ridged->primitives[0];
  ASSERT_TRUE(p.normal_map);
  EXPECT_EQ(p.normal_map_source.procedural, "ridges");
  EXPECT_EQ(p.normal_map, LoadNormalMap(p.normal_map_source).value());  // the process's one copy
  EXPECT_NE(p.normal_map, base->primitives[0].normal_map);
  EXPECT_EQ(p.normal_map_scale, base->primitives[0].normal_map_scale);
  EXPECT_EQ(ridged->rig.distance, base->rig.distance);
  EXPECT_EQ(ridged->material.alpha, base->material.alpha);

  const std::pair<const char*, const char*> bad[] = {
      {"sphere@bumps", "'sphere' has no normal map for 'bumps' to replace"},
      {"nm-plane@no-such-map.png", "no-such-map.png"},
      {"nm-plane@", "needs both a scene and a normal map"},
      {"@bumps", "needs both a scene and a normal map"},
      {"no-such-scene@bumps", "unknown scene 'no-such-scene'"},
  };
  for (const auto& [name, message] : bad) {
    auto s = LoadScene(name);
    ASSERT_FALSE(s.ok()) << name;
    EXPECT_NE(s.error().find(message), std::string::npos) << name << ": " << s.error();
  }
}

TEST(CameraPath, DeterministicMovingAndOrthonormal) {
  CameraRig rig;
  for (auto name : CameraPathNames()) {
    const std::string_view path = name;
    const CameraPath camera = *ParseCameraPath(name);
    EXPECT_EQ(CameraPathName(camera), name);
    auto a = CameraAt(camera, rig, 7, 30, 64, 48);
    auto b = CameraAt(camera, rig, 7, 30, 64, 48);
    EXPECT_EQ(a.pos, b.pos) << path;
    EXPECT_EQ(a.fwd, b.fwd) << path;
    EXPECT_NEAR(glm::length(a.fwd), 1, 1e-12);
    EXPECT_NEAR(glm::dot(a.fwd, a.right), 0, 1e-12);
    EXPECT_NEAR(glm::dot(a.up, a.right), 0, 1e-12);
    auto c = CameraAt(camera, rig, 8, 30, 64, 48);
    if (path != "static") {
      EXPECT_GT(glm::length(c.pos - a.pos), 0.0) << path;
    }
  }
  // vr-jitter stays within a few millimetres per metre of viewing distance.
  auto base = CameraAt(scene::CameraPath::kStatic, rig, 0, 30, 64, 64);
  for (int f = 0; f < 90; ++f)
    EXPECT_LT(glm::length(CameraAt(scene::CameraPath::kVrJitter, rig, f, 90, 64, 64).pos - base.pos),
              0.01 * rig.distance);
  // dolly halves the distance every 2 s.
  auto d = CameraAt(scene::CameraPath::kDolly, rig, 60, 30, 64, 64);
  EXPECT_NEAR(glm::length(d.pos - rig.target), rig.distance / 2, 1e-9);
  // orbit keeps the distance and turns 45 degrees per second.
  auto o = CameraAt(scene::CameraPath::kOrbit, rig, 30, 30, 64, 64);
  EXPECT_NEAR(glm::length(o.pos - rig.target), rig.distance, 1e-9);
  EXPECT_NEAR(std::acos(glm::dot(glm::normalize(o.pos), glm::normalize(base.pos))) * 180 / 3.14159265358979,
              45 * std::cos(rig.elevation_deg * 3.14159265358979 / 180) * 1.0, 1.0);
}

TEST(PackScene, HeaderCountsAndBvhBounds) {
  auto s = LoadScene("sphere-field").value();
  auto words = PackScene(s);
  int bounded = int(words[0].x), nodes = int(words[0].y), first = int(words[0].z), unbounded = int(words[0].w);
  EXPECT_EQ(bounded + unbounded, int(s.primitives.size()));
  EXPECT_EQ(unbounded, 1);
  EXPECT_EQ(first, 1 + 2 * nodes);
  EXPECT_EQ(int(words.size()), first + 3 * (bounded + unbounded));
  // The root box contains every bounded primitive's centre.
  for (int i = 0; i < bounded; ++i) {
    glm::vec4 c = words[first + 3 * i + 1];
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(c[k], words[1][k]);
      EXPECT_LE(c[k], words[2][k]);
    }
  }
}

}  // namespace
}  // namespace shimmer::scene
