// A Blender Python script that builds one shimmer shot for Cycles: an
// independent renderer to check shimmer's reference against
// (docs/renderer.md, "Checking the reference with Blender Cycles").
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "shimmer/core/result.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::experiments {

struct BlenderShot {
  scene::Scene scene;
  shading::MaterialDesc material;  // the scene's, or --material's
  scene::CameraPath camera_path = scene::CameraPath::kOrbit;
  int frame = 0;
  double fps = 30;
  int width = 64;
  int height = 64;
  bool specular_only = false;  // drop the diffuse lobe
  int default_spp = 256;       // the script's --spp when none is given
};

// The shot in the script's data block: the camera of `camera_path` at
// `frame`, the primitives, the light and the material, in shimmer's own
// (y-up) coordinates; the script converts to Blender's z-up frame. Errors
// (bad input) name what Cycles cannot reproduce: bump-mapped planes and
// anisotropic roughness.
Result<nlohmann::json> BlenderShotData(const BlenderShot& shot);

// The whole script: `blender -b --factory-startup -P scene.py -- --out x.exr
// [--spp N] [--threads T] [--seed S]` renders the shot into a linear float
// EXR. The data block sits between the lines "# --- shot ---" and
// "# --- end shot ---" as one JSON line, for tools and tests to read back.
Result<std::string> BlenderScript(const BlenderShot& shot);

}  // namespace shimmer::experiments
