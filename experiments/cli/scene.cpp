// shimmer scene validate FILE | shimmer scene preview FILE -o scene.png
//
// A scene author's loop: check the file (every error names the JSON Pointer
// of the key at fault) and look at it, without rendering a sequence.
#include <cstdio>
#include <memory>

#include "commands.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::cli {

namespace {

struct SceneOptions {
  std::string scene;
  std::string material;
  std::string camera = "orbit";
  int frame = 0;
  std::vector<int> size{512, 512};
  std::string device;
  std::string out;
};

void Validate(const SceneOptions& o) {
  const scene::Scene s = Take(scene::LoadScene(o.scene));
  int counts[3] = {0, 0, 0};
  for (const scene::Primitive& p : s.primitives) ++counts[static_cast<int>(p.type)];
  std::printf(
      "%s: valid scene '%s': %zu primitives (%d spheres, %d capsules, %d planes), %s light, material %s, "
      "camera %g from (%g, %g, %g) at %g deg elevation, fov %g deg\n",
      o.scene.c_str(), s.name.c_str(), s.primitives.size(), counts[0], counts[1], counts[2],
      std::string(shading::LightTypeName(s.light.type)).c_str(), scene::MaterialSpec(s.material).c_str(),
      s.rig.distance, s.rig.target.x, s.rig.target.y, s.rig.target.z, s.rig.elevation_deg, s.rig.fov_y_deg);
}

void Preview(const SceneOptions& o) {
  render::RenderSettings s;
  s.scene = Take(scene::LoadScene(o.scene));
  s.material = o.material.empty() ? s.scene.material : Take(scene::ParseMaterial(o.material, s.scene.material));
  s.camera = CameraPathOption(o.camera);
  s.width = o.size[0];
  s.height = o.size[1];
  s.frames = o.frame + 1;
  // Analytic derivatives: the picture is the same, and any device can run it.
  s.derivatives = shading::DerivativeSource::kAnalytic;
  s.device = o.device;
  RequireParentDirectory("-o", o.out);
  auto renderer = Take(render::Renderer::Create(s), {{"width and height", "--size"}, {"frames", "--frame"}});
  const render::Frame frame = Take(renderer->RenderFrame(o.frame));
  Check(render::WritePreviewPng(o.out, frame));
  std::printf("%s: frame %d of %s (%s, %dx%d, variant none) -> %s\n", o.scene.c_str(), o.frame,
              std::string(scene::CameraPathName(s.camera)).c_str(), scene::MaterialSpec(s.material).c_str(), s.width,
              s.height, o.out.c_str());
}

}  // namespace

void AddSceneCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("scene", "Check a scene file, or render a preview of it");
  cmd->require_subcommand(1);
  cmd->footer("Scene files: docs/scenes.md (every key, its type, unit and default).");

  auto v = std::make_shared<SceneOptions>();
  CLI::App* validate = cmd->add_subcommand("validate", "Check a scene file; print what it holds, or the first error");
  validate->add_option("scene", v->scene, "JSON scene file (or a built-in scene name)")->required();
  validate->callback([v] { Validate(*v); });

  auto p = std::make_shared<SceneOptions>();
  CLI::App* preview = cmd->add_subcommand("preview", "Render one frame of a scene (variant none) to a PNG");
  preview->add_option("scene", p->scene, "JSON scene file (or a built-in scene name)")->required();
  preview->add_option("-o,--out", p->out, "PNG to write")->required();
  preview->add_option("--material", p->material, "Material spec (default: the scene's)");
  preview->add_option("--camera", p->camera, "Camera path")->capture_default_str();
  preview->add_option("--frame", p->frame, "Frame of the camera path (at 30 fps)")
      ->check(CLI::Range(0, render::kMaxFrames - 1))
      ->capture_default_str();
  preview->add_option("--size", p->size, "Width and height in pixels")
      ->expected(2)
      ->check(CLI::Range(1, render::kMaxImageSide))
      ->capture_default_str();
  preview->add_option("--device", p->device, "Vulkan device (substring of its name)");
  preview->callback([p] { Preview(*p); });
}

}  // namespace shimmer::cli
