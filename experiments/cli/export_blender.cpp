// `shimmer export-blender`: writes a Blender Python script that renders one
// frame of a shimmer shot with Cycles, an independent check of the reference.
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "shimmer/core/atomic_file.h"
#include "shimmer/experiments/blender_script.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::cli {

namespace {

struct ExportBlenderOptions {
  std::string scene;
  std::string material;
  std::string camera = "orbit";
  int frame = 0;
  int frames = 16;
  double fps = 30;
  std::vector<int> size{96, 96};
  bool specular_only = false;
  int spp = 256;
  std::string out;
};

void Run(const ExportBlenderOptions& o) {
  experiments::BlenderShot shot;
  shot.scene = Take(scene::LoadScene(o.scene), {{"unknown scene", "SCENE: unknown scene"}});
  shot.material = shot.scene.material;
  if (!o.material.empty()) shot.material = Take(scene::ParseMaterial(o.material, shot.scene.material));
  const scene::CameraPath camera = CameraPathOption(o.camera);
  if (o.frames < 1) throw UsageError("--frames must be >= 1, got " + std::to_string(o.frames));
  if (o.frame < 0 || o.frame >= o.frames)
    throw UsageError("--frame " + std::to_string(o.frame) + " is out of range: the sequence has --frames " +
                     std::to_string(o.frames) + " (frames 0.." + std::to_string(o.frames - 1) + ")");
  shot.camera_path = camera;
  shot.frame = o.frame;
  shot.fps = o.fps;
  shot.width = o.size[0];
  shot.height = o.size[1];
  shot.specular_only = o.specular_only;
  shot.default_spp = o.spp;
  std::error_code ec;
  if (std::filesystem::is_directory(o.out, ec)) throw UsageError("-o " + o.out + ": is a directory, not a file");
  RequireParentDirectory("-o", o.out);
  const std::string script =
      Take(experiments::BlenderScript(shot),
           {{"width and height", "--size"}, {"fps", "--fps"}, {"spp", "--spp"}, {"frame", "--frame"}});
  Check(WriteFileAtomic(o.out, script));
  std::printf(
      "%s: %s (%s, frame %d) at %dx%d for Blender Cycles; run: blender -b --factory-startup -P %s -- --out "
      "shot.exr --spp %d\n",
      o.out.c_str(), shot.scene.name.c_str(), o.camera.c_str(), o.frame, shot.width, shot.height, o.out.c_str(), o.spp);
}

}  // namespace

void AddExportBlenderCommand(CLI::App& app) {
  auto o = std::make_shared<ExportBlenderOptions>();
  CLI::App* cmd =
      app.add_subcommand("export-blender", "Write a Blender Python script rendering one frame of a shot with Cycles");
  cmd->footer(
      "Run the script with: blender -b --factory-startup -P scene.py -- --out shot.exr [--spp N] [--threads T]\n"
      "  [--seed S]; it writes a linear float OpenEXR of direct light only (box filter 1 px).\n"
      "Not reproduced: bump-mapped planes (refused), anisotropic roughness (refused), shimmer's height-correlated\n"
      "  Smith G (Cycles uses G1*G1), exact capsule sides (128-sided smooth cylinders). docs/renderer.md has the\n"
      "  measured comparison.");
  cmd->add_option("scene", o->scene, "Built-in scene name or JSON scene file")->required();
  cmd->add_option("--material", o->material, "Material spec (default: the scene's)");
  cmd->add_option("--camera", o->camera, "Camera path")->capture_default_str();
  cmd->add_option("--frame", o->frame, "Frame of the camera path (0-based)")->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames in the sequence (--frame must be below)")->capture_default_str();
  cmd->add_option("--fps", o->fps, "Frames per second (camera time step)")->capture_default_str();
  cmd->add_option("--size", o->size, "Width and height in pixels (1..16384)")->expected(2)->capture_default_str();
  cmd->add_flag("--specular-only", o->specular_only, "Leave out the diffuse lobe");
  cmd->add_option("--spp", o->spp, "The script's default samples per pixel")->capture_default_str();
  cmd->add_option("-o,--out", o->out, "Output Python script")->required();
  cmd->callback([o] { Run(*o); });
}

}  // namespace shimmer::cli
