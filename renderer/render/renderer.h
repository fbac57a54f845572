// Renders camera-motion sequences with the Vulkan kernel: one dispatch per
// frame (one per round for the adaptive reference), frames read back as
// planar float channels, written as multi-layer EXR beside a sequence.json.
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "scene.h"
#include "shading.h"

namespace shimmer::render {

// Planes of a frame, in the kernel's order (render.comp CH_*).
enum Channel : int {
  kBeautyR = 0,
  kSpecularR = 3,
  kDiffuseR = 6,
  kMotionX = 9,
  kDepth = 11,
  kNormalX = 12,
  kRoughness = 15,
  kFootprintX = 16,
  kStderr = 18,
  kSampleCount = 19,
  kLuminanceM2 = 20,
  kChannelCount = 21,
};

struct ExrChannel {
  const char* name;
  int plane;
};
// The EXR layers of DESIGN.md; stderr.Y only for the reference.
std::vector<ExrChannel> ExrChannels(bool with_stderr);

#ifdef NDEBUG
inline constexpr bool kValidationByDefault = false;
#else
inline constexpr bool kValidationByDefault = true;
#endif

struct RenderSettings {
  scene::Scene scene;
  shading::MaterialDesc material;
  std::string camera = "orbit";
  double fps = 30;
  int width = 96;
  int height = 96;
  int frames = 16;
  std::string variant = "none";  // catalogue name or supersample-N; ignored with variant_file
  std::vector<std::pair<std::string, double>> param_overrides;
  shading::DerivativeSource derivatives = shading::DerivativeSource::kQuadFine;
  int reference_spp = 0;           // N: N x N stratified samples of `none` with a stderr layer (0: not a reference)
  double reference_tolerance = 0;  // > 0: adaptive, rounds of N x N until stderr <= tolerance * max(Y, floor)
  int max_rounds = 64;             // adaptive cap
  std::string variant_file;        // user variant GLSL defining userVariant(...)
  std::string device;              // substring of the Vulkan device name
  std::string preview_png;         // when set: a tone-mapped PNG of frame 0's beauty
  // Khronos validation layer (when installed); anything it reports fails the
  // render. On by default in debug builds.
  bool validation = kValidationByDefault;
  int lose_device_after_dispatches = -1;  // fault injection for tests, see vk::ContextOptions
  // Rows per dispatch (a multiple of 8). 0: as many as the device's storage
  // buffer range allows (lavapipe: 128 MiB, about 1.6 M pixels of all the
  // layers); taller images render in bands of that many rows.
  int band_rows = 0;
  // ZIP for frames people keep; none for frames measured once and deleted
  // (the experiment runner's): zlib then costs more than the rendering.
  bool compress_exr = true;
};

// Luminance floor of the adaptive reference's relative error (dark pixels
// would otherwise never converge).
constexpr double kReferenceLuminanceFloor = 1e-2;

struct Frame {
  int width = 0;
  int height = 0;
  std::vector<float> planes;  // kChannelCount planes of width * height
  double gpu_ms = 0;          // timestamps, all dispatches of the frame
  double readback_ms = 0;
  int rounds = 1;
  double mean_spp = 1;
  float at(int channel, int x, int y) const {
    return planes[std::size_t(channel) * width * height + std::size_t(y) * width + x];
  }
};

struct Timings {
  double compile_ms = 0;   // GLSL -> SPIR-V (0 when cached in this process)
  double pipeline_ms = 0;  // vkCreateComputePipelines
  double jit_ms = 0;       // first (warm-up) dispatch: lavapipe's LLVM JIT
};

// Resolved from RenderSettings; describes what is rendered.
struct ResolvedVariant {
  std::string name;
  int id = 0;
  int spp_n = 1;
  bool reference = false;
  shading::Params<double> params;
  std::vector<std::pair<std::string, double>> shown_params;  // the variant's own parameters with values
};

class Renderer {
 public:
  // Validates settings, opens the device, compiles the kernel. On failure the
  // error names the cause (no device, unknown variant, compile error with file:line, ...).
  static std::pair<std::unique_ptr<Renderer>, std::string> Create(const RenderSettings& settings);
  ~Renderer();

  struct Result {
    Frame frame;
    std::string error;
  };
  Result RenderFrame(int index);

  const RenderSettings& settings() const;
  const ResolvedVariant& variant() const;
  const Timings& timings() const;
  std::string device_name() const;
  bool validation_active() const;  // the validation layer was asked for and is loaded
  std::span<const glm::vec4> scene_words() const;
  shading::CameraDesc camera(int frame) const;

 private:
  Renderer();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The source revision compiled in (git describe at configure time).
std::string SourceRevision();

// Renders settings.frames frames into out_dir (frame_NNNN.exr + sequence.json),
// writing EXR on a worker thread while the next frame renders. sequence.json
// says "status": "running" until every frame is on disk, then "complete"; a
// frame that fails to render (device lost, a validation message) makes it
// "failed" with the "error", the frames before it left whole.
// Returns an error message, empty on success. `progress(done, total)` after each frame.
std::string RenderSequence(const RenderSettings& settings, const std::string& out_dir,
                           const std::function<void(int, int)>& progress);

// Writes a tone-mapped (x / (1 + x), sRGB) 8-bit PNG of the beauty layer.
std::string WritePreviewPng(const std::string& path, const Frame& frame);

// Writes one frame as float EXR to path (through path.tmp and a rename),
// ZIP-compressed or not.
std::string WriteExr(const std::string& path, const Frame& frame, bool with_stderr, bool compress = true);

}  // namespace shimmer::render
