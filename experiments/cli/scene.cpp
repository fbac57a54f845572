// shimmer scene validate FILE | shimmer scene preview FILE -o scene.png
//
// A scene author's loop: check the file (every error names the JSON Pointer
// of the key at fault, or the asset file and its problem) and look at it,
// without rendering a sequence.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>

#include "commands.h"
#include "shimmer/renderer/mesh_loading.h"
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

bool IsAssetFile(const std::string& file) {
  std::string extension = std::filesystem::path(file).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  return extension == ".gltf" || extension == ".glb" || extension == ".obj";
}

// A mesh asset: what it holds (meshes, triangles, materials as shimmer reads
// them, its bounds), then each warning of the loader (normals or tangents
// computed, zero-area triangles or UV triangles) on a line of its own.
void ValidateAsset(const std::string& file) {
  const scene::MeshAsset asset = Take(scene::LoadMeshAsset(file));
  std::size_t vertices = 0;
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
  for (const scene::TriangleMesh& m : asset.meshes) {
    vertices += m.positions.size();
    for (const glm::vec3& p : m.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  }
  std::printf("%s: valid asset: %zu meshes, %zu triangles, %zu vertices, bounds (%g, %g, %g) to (%g, %g, %g)\n",
              file.c_str(), asset.meshes.size(), asset.triangle_count(), vertices, lo.x, lo.y, lo.z, hi.x, hi.y,
              hi.z);
  for (const scene::TriangleMesh& m : asset.meshes)
    std::printf("  %s: %zu triangles, material '%s': roughness %g (alpha %g), normal texture %s, roughness texture %s\n",
                m.name.empty() ? "(unnamed mesh)" : m.name.c_str(), m.triangle_count(), m.material.name.c_str(),
                m.material.roughness, m.material.alpha(), m.material.normal_texture.present() ? "yes" : "no",
                m.material.metallic_roughness_texture.present() ? "yes" : "no");
  for (const std::string& w : asset.warnings) std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
}

void Validate(const SceneOptions& o) {
  if (IsAssetFile(o.scene)) return ValidateAsset(o.scene);
  const scene::Scene s = Take(scene::LoadScene(o.scene));
  int counts[4] = {0, 0, 0, 0};
  std::size_t triangles = 0;
  for (const scene::Primitive& p : s.primitives) {
    ++counts[static_cast<int>(p.type)];
    if (p.mesh) {
      triangles += p.mesh->mesh.triangle_count();
      for (const std::string& w : p.mesh->warnings) std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
    }
  }
  // Scenes without assets print what they printed before meshes.
  const std::string meshes = counts[3] == 0 ? std::string()
                                            : ", " + std::to_string(counts[3]) + " meshes of " +
                                                  std::to_string(triangles) + " triangles";
  std::printf(
      "%s: valid scene '%s': %zu primitives (%d spheres, %d capsules, %d planes%s), %s light, material %s, "
      "camera %g from (%g, %g, %g) at %g deg elevation, fov %g deg\n",
      o.scene.c_str(), s.name.c_str(), s.primitives.size(), counts[0], counts[1], counts[2], meshes.c_str(),
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
  CLI::App* validate = cmd->add_subcommand(
      "validate", "Check a scene file or a mesh asset (.gltf, .glb, .obj); print what it holds, or the first error");
  validate->add_option("scene", v->scene, "JSON scene file, built-in scene name, or mesh asset file")->required();
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
