// The Blender script generator without Blender: the data block carries
// shimmer's own camera for the frame, every primitive and the light, and what
// Cycles cannot reproduce is refused with a message naming it.
#include <gtest/gtest.h>

#include <cmath>

#include "shimmer/experiments/blender_script.h"

namespace shimmer::experiments {
namespace {

BlenderShot Shot(const std::string& scene_name, scene::CameraPath path, int frame) {
  BlenderShot shot;
  shot.scene = scene::LoadScene(scene_name).value();
  shot.material = shot.scene.material;
  shot.camera_path = path;
  shot.frame = frame;
  shot.width = 80;
  shot.height = 48;
  return shot;
}

// The JSON between the script's shot markers, parsed back.
nlohmann::json ShotBlock(const std::string& script) {
  const std::string begin = "# --- shot ---\nSHOT = json.loads(r'''", end = "''')\n# --- end shot ---";
  const auto b = script.find(begin), e = script.find(end);
  EXPECT_NE(b, std::string::npos);
  EXPECT_NE(e, std::string::npos);
  if (b == std::string::npos || e == std::string::npos) return {};
  return nlohmann::json::parse(script.substr(b + begin.size(), e - b - begin.size()));
}

void ExpectVec(const nlohmann::json& j, glm::dvec3 v) {
  ASSERT_EQ(j.size(), 3u);
  EXPECT_EQ(j[0].get<double>(), v.x);
  EXPECT_EQ(j[1].get<double>(), v.y);
  EXPECT_EQ(j[2].get<double>(), v.z);
}

TEST(BlenderScript, CameraIsShimmersCameraForThatFrame) {
  for (auto path : {scene::CameraPath::kOrbit, scene::CameraPath::kDolly, scene::CameraPath::kVrJitter}) {
    const BlenderShot shot = Shot("sphere-field", path, 7);
    const auto script = BlenderScript(shot);
    ASSERT_TRUE(script) << script.error();
    const nlohmann::json cam = ShotBlock(*script)["camera"];
    const shading::CameraDesc c = scene::CameraAt(path, shot.scene.rig, 7, 30, 80, 48);
    ExpectVec(cam["pos"], c.pos);
    ExpectVec(cam["fwd"], c.fwd);
    ExpectVec(cam["right"], c.right);
    ExpectVec(cam["up"], c.up);
    EXPECT_EQ(cam["tan_half_fov_y"].get<double>(), c.tan_half_fov_y);
    EXPECT_NEAR(cam["fov_y_deg"].get<double>(), shot.scene.rig.fov_y_deg, 1e-9);
    EXPECT_EQ(cam["width"], 80);
    EXPECT_EQ(cam["height"], 48);
    EXPECT_EQ(cam["frame"], 7);
  }
  // Another frame is another camera: the frame is not ignored.
  const auto a = ShotBlock(*BlenderScript(Shot("sphere", scene::CameraPath::kOrbit, 0)));
  const auto b = ShotBlock(*BlenderScript(Shot("sphere", scene::CameraPath::kOrbit, 9)));
  EXPECT_NE(a["camera"]["pos"], b["camera"]["pos"]);
}

TEST(BlenderScript, EveryPrimitiveAndTheLightAppear) {
  const BlenderShot field = Shot("sphere-field", scene::CameraPath::kOrbit, 0);
  const nlohmann::json j = ShotBlock(*BlenderScript(field));
  ASSERT_EQ(j["spheres"].size() + j["planes"].size(), field.scene.primitives.size());
  for (std::size_t i = 0; i < j["spheres"].size(); ++i) {
    const scene::Primitive& p = field.scene.primitives[i];
    EXPECT_EQ(j["spheres"][i][0].get<double>(), p.a.x);
    EXPECT_EQ(j["spheres"][i][1].get<double>(), p.a.y);
    EXPECT_EQ(j["spheres"][i][2].get<double>(), p.a.z);
    EXPECT_EQ(j["spheres"][i][3].get<double>(), p.radius);
  }
  EXPECT_EQ(j["light"]["type"], "sun");
  ExpectVec(j["light"]["direction"], field.scene.light.vec);
  ExpectVec(j["light"]["irradiance"], field.scene.light.radiance);
  EXPECT_DOUBLE_EQ(j["material"]["roughness"].get<double>(), std::sqrt(field.material.alpha.x));

  BlenderShot wires = Shot("wires", scene::CameraPath::kOrbit, 0);
  wires.material.alpha = {0.1, 0.1};
  const nlohmann::json w = ShotBlock(*BlenderScript(wires));
  ASSERT_EQ(w["capsules"].size(), wires.scene.primitives.size());
  EXPECT_EQ(w["capsules"][3][6].get<double>(), wires.scene.primitives[3].radius);
  EXPECT_EQ(w["light"]["type"], "point");
  ExpectVec(w["light"]["position"], wires.scene.light.vec);
}

TEST(BlenderScript, QuotesInANameCannotEndTheDataBlock) {
  BlenderShot shot = Shot("sphere", scene::CameraPath::kStatic, 0);
  shot.scene.name = "a'''b\nc";
  const auto script = BlenderScript(shot);
  ASSERT_TRUE(script) << script.error();
  EXPECT_EQ(ShotBlock(*script)["scene"], "a'''b\nc");
}

TEST(BlenderScript, RefusesWhatCyclesCannotReproduce) {
  const auto bumpy = BlenderScript(Shot("bumpy-plane", scene::CameraPath::kOrbit, 0));
  ASSERT_FALSE(bumpy);
  EXPECT_EQ(bumpy.code(), ErrorCode::kBadInput);
  EXPECT_NE(bumpy.error().find("bump"), std::string::npos) << bumpy.error();

  const auto wires = BlenderScript(Shot("wires", scene::CameraPath::kOrbit, 0));  // alpha 0.04 x 0.2
  ASSERT_FALSE(wires);
  EXPECT_NE(wires.error().find("anisotropic"), std::string::npos) << wires.error();

  BlenderShot negative = Shot("sphere", scene::CameraPath::kOrbit, -1);
  EXPECT_FALSE(BlenderScript(negative));
}

}  // namespace
}  // namespace shimmer::experiments
