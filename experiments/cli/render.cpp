// `shimmer render`: renders a camera-motion sequence (or its reference) with
// the Vulkan compute renderer into EXR frames and a sequence.json.
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::cli {

namespace {

struct RenderOptions {
  std::string scene = "sphere-field";
  std::string asset;
  std::string material;
  std::string camera = "orbit";
  std::string variant = "none";
  std::string variant_file;
  std::vector<std::string> params;
  std::string derivatives = "quad";
  int frames = 16;
  std::vector<int> size{96, 96};
  double fps = 30;
  int reference_spp = 0;
  int reference_replicates = 4;
  double reference_tolerance = 0;
  int max_rounds = 64;
  std::uint32_t seed = 0;
  std::string device;
  std::string out = "shimmer-render";
  bool list_devices = false;
  std::string preview;
};

void PrintProgress(int done, int total) {
  const int width = 30;
  int filled = total > 0 ? done * width / total : width;
  std::fprintf(stderr, "\r[%.*s%*s] %d/%d frames", filled, "##############################", width - filled, "", done,
               total);
  if (done == total) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

// RenderSettings' field names in library messages, as the flags the user typed.
const FieldFlags kRenderFlags = {{"width and height", "--size"},
                                 {"frames", "--frames"},
                                 {"fps", "--fps"},
                                 {"reference_spp", "--reference-spp"},
                                 {"reference_replicates", "--reference-replicates"},
                                 {"reference_tolerance", "--reference-tolerance"},
                                 {"max_rounds", "--max-rounds"},
                                 {"a reference renders variant none, not a variant file",
                                  "--reference-spp and --reference-tolerance render variant none; drop --variant-file"},
                                 {"a reference is already supersampled; use variant none with reference_spp",
                                  "a reference is already supersampled; use --variant none with --reference-spp"}};

void Run(const RenderOptions& o, const CLI::App& cmd) {
  if (o.list_devices) {
    for (const auto& d : Take(render::ListDevices()))
      std::printf("%s (%s, %s, subgroup %u%s)\n", d.name.c_str(), d.type.c_str(), d.driver.c_str(), d.subgroup_size,
                  d.quad_ops ? ", quad ops" : "");
    return;
  }
  RequireOneFilter(cmd, o.variant, o.variant_file);
  render::RenderSettings s;
  if (!o.asset.empty()) {
    if (cmd.count("--scene") > 0) throw UsageError("--asset and --scene: give one of them");
    s.scene = Take(scene::AssetScene(o.asset));
    for (const std::string& w : s.scene.primitives.front().mesh->warnings)
      std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
  } else {
    s.scene = Take(scene::LoadScene(o.scene), {{"unknown scene", "--scene: unknown scene"}});
  }
  s.material = s.scene.material;
  if (!o.material.empty()) s.material = Take(scene::ParseMaterial(o.material, s.scene.material));
  s.camera = CameraPathOption(o.camera);
  s.variant = o.variant;
  s.variant_file = o.variant_file;
  for (const std::string& p : o.params) s.param_overrides.push_back(ParseParamOption(p));
  const auto derivatives = shading::ParseDerivativeSource(o.derivatives);
  if (!derivatives)
    throw UsageError("--derivatives must be " + std::string(shading::kDerivativeSourceList) + ", got '" +
                     o.derivatives + "'");
  s.derivatives = *derivatives;
  s.frames = o.frames;
  s.width = o.size[0];
  s.height = o.size[1];
  s.fps = o.fps;
  s.reference_spp = o.reference_spp;
  s.reference_tolerance = o.reference_tolerance;
  if (o.reference_tolerance > 0 && o.reference_spp == 0) s.reference_spp = 4;
  s.reference_replicates = o.reference_replicates;
  s.max_rounds = o.max_rounds;
  s.seed = o.seed;
  s.device = o.device;
  s.preview_png = o.preview;
  if (!o.preview.empty()) RequireParentDirectory("--preview", o.preview);
  // The outermost directory of --out that the render would create.
  std::error_code ec;
  std::filesystem::path created;
  for (std::filesystem::path p = o.out; !p.empty() && !std::filesystem::exists(p, ec) && p != p.parent_path();
       p = p.parent_path())
    created = p;
  const bool preview_existed = !o.preview.empty() && std::filesystem::exists(o.preview, ec);
  const bool tty = isatty(fileno(stderr));
  auto rendered = render::RenderSequence(s, o.out, tty ? PrintProgress : std::function<void(int, int)>());
  if (!rendered) {
    // A sequence this command began and could not finish is not left behind,
    // nor its preview. (Rendered into a directory that was there, the frames
    // before the failure stay, and sequence.json says "failed" and why.)
    if (!created.empty()) std::filesystem::remove_all(created, ec);
    if (!o.preview.empty() && !preview_existed) std::filesystem::remove(o.preview, ec);
  }
  const SequenceFile seq = Take(std::move(rendered), kRenderFlags);
  std::printf("%d frames of %s (%s, %s) at %dx%d in %s: %.2f ms/frame on %s\n", s.frames, s.scene.name.c_str(),
              seq.camera.path.c_str(), seq.variant.c_str(), s.width, s.height, o.out.c_str(), seq.MeanGpuMs(),
              seq.device.c_str());
  if (!o.preview.empty()) std::printf("preview: %s\n", o.preview.c_str());
  long long unconverged = 0;
  int frames = 0;
  for (const SequenceFrame& f : seq.frames)
    if (f.unconverged_pixels.value_or(0) > 0) unconverged += *f.unconverged_pixels, ++frames;
  if (unconverged > 0)
    std::fprintf(stderr,
                 "shimmer: warning: %lld pixels in %d of %zu frames stayed above --reference-tolerance %g at "
                 "--max-rounds %d\n",
                 unconverged, frames, seq.frames.size(), s.reference_tolerance,
                 std::max(s.max_rounds, s.reference_replicates));
}

}  // namespace

void AddRenderCommand(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  CLI::App* cmd = app.add_subcommand("render", "Render a camera-motion sequence to EXR frames (Vulkan compute)");
  cmd->footer(
      "Material spec: NDF:ALPHA[,ALPHA_Y][,f0=V|R/G/B][,albedo=V|R/G/B]\n"
      "  e.g. ggx:0.05   beckmann:0.02,0.1   ggx:0.1,f0=0.9/0.6/0.3,albedo=0   blinn-phong:200 (a power)\n"
      "  glints:ALPHA[,ALPHA_Y][,local=ALPHA_L][,density=N]: glints (docs/glints.md), e.g. glints:0.3,local=0.03\n"
      "Scenes: sphere, sphere-field, wires, bumpy-plane, sg-sphere-field, sg-plane, sg-bumpy-plane,\n"
      "  nm-plane, nm-sphere, nm-magnify (normal-mapped), glint-plane, glint-sphere (glints),\n"
      "  or a JSON file (docs/scenes.md).\n"
      "Assets: --asset FILE (.gltf, .glb, .obj) renders a mesh alone: a directional key light, the default\n"
      "  material (--material overrides) and the camera path about a rig that frames its bounds.\n"
      "Camera paths: orbit, pan, dolly, vr-jitter, static.\n"
      "Output: DIR/frame_NNNN.exr (R,G,B, specular.*, diffuse.*, motion.X/Y, depth.Z, normal.*,\n"
      "  roughness.A, footprint.X/Y, stderr.Y for the reference) and DIR/sequence.json.");
  cmd->add_option("--scene", o->scene, "Built-in scene name or JSON scene file")->capture_default_str();
  cmd->add_option("--asset", o->asset, "A mesh asset (.gltf, .glb, .obj) to render alone, framed (instead of --scene)");
  cmd->add_option("--material", o->material, "Material spec (default: the scene's)");
  cmd->add_option("--camera", o->camera, "Camera path")->capture_default_str();
  cmd->add_option("--variant", o->variant, "Filter variant (`shimmer variants`) or supersample-N")
      ->capture_default_str();
  cmd->add_option("--variant-file", o->variant_file,
                  "GLSL file defining FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, "
                  "VariantParams p); compiled at run time (instead of --variant)");
  cmd->add_option("--param", o->params, "Variant parameter name=value (repeatable)");
  cmd->add_option("--derivatives", o->derivatives, "quad (= quad-fine), quad-coarse or analytic")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "Number of frames")->capture_default_str();
  cmd->add_option("--size", o->size, "Width and height in pixels (1..16384)")->expected(2)->capture_default_str();
  cmd->add_option("--fps", o->fps, "Frames per second (camera time step; metadata)")->capture_default_str();
  auto spp = cmd->add_option("--reference-spp", o->reference_spp,
                             "Render the reference: variant none with N x N stratified samples per pixel");
  cmd->add_option("--reference-replicates", o->reference_replicates,
                  "Reference: K independent N x N patterns per pixel (2..4096); their spread is the standard "
                  "error (stderr.Y)")
      ->capture_default_str();
  cmd->add_option("--reference-tolerance", o->reference_tolerance,
                  "Adaptive reference: K rounds of N x N samples (N = --reference-spp, default 4), then more "
                  "until the standard error is below T times max(luminance, 0.01)");
  cmd->add_option("--max-rounds", o->max_rounds, "Adaptive reference: most rounds per frame (at least K)")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed,
                  "Random seed of the reference's samples (renders with different seeds are "
                  "independent)")
      ->capture_default_str();
  cmd->add_option("--device", o->device, "Vulkan device (substring of its name)");
  cmd->add_option("--preview", o->preview, "Also write a tone-mapped PNG of frame 0 to this file");
  cmd->add_flag("--list-devices", o->list_devices, "List Vulkan devices and exit");
  cmd->add_option("--out", o->out, "Output directory")->capture_default_str();
  (void)spp;
  cmd->callback([o, cmd] { Run(*o, *cmd); });
}

}  // namespace shimmer::cli
