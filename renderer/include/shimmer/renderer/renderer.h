// Renders camera-motion sequences with the Vulkan kernel: one dispatch per
// frame (per band of rows for images larger than a storage buffer, per round
// for the adaptive reference), frames read back as planar float channels,
// written as multi-layer EXR beside a sequence.json.
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/core/sequence_file.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"
#include "shimmer/shading/user_variant.h"

namespace shimmer::render {

// Planes of a frame, in the kernel's order (channels.glsl CH_*; gpu_layout.h
// asserts that they agree).
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

struct FrameChannel {
  const char* name;  // the EXR channel name, e.g. "specular.R"
  int plane;         // a Channel
};
// The EXR channels of a frame file; stderr.Y only for the reference.
std::vector<FrameChannel> FrameChannels(bool with_stderr);

#ifdef NDEBUG
inline constexpr bool kValidationByDefault = false;
#else
inline constexpr bool kValidationByDefault = true;
#endif

struct RenderSettings {
  scene::Scene scene;
  shading::MaterialDesc material;
  scene::CameraPath camera = scene::CameraPath::kOrbit;
  double fps = 30;
  int width = 96;
  int height = 96;
  int frames = 16;
  std::string variant = "none";  // catalogue name or supersample-N; ignored with variant_file
  std::vector<std::pair<std::string, double>> param_overrides;
  shading::DerivativeSource derivatives = shading::DerivativeSource::kQuadFine;
  int reference_spp = 0;  // N: N x N stratified samples of `none` with a stderr layer (0: not a reference)
  // K: a reference pixel is the mean of at least K replicates, each a full
  // N x N jittered pattern with its own jitter (one round each); stderr.Y is
  // the spread of their means. A fixed reference renders exactly K rounds.
  int reference_replicates = 4;
  double reference_tolerance = 0;  // > 0: adaptive, K rounds, then more until stderr <= tolerance * max(Y, floor)
  int max_rounds = 64;             // adaptive cap (at least K rounds are rendered)
  // Mixed into every sample's random numbers: renders with different seeds are
  // independent estimates of the same frame. 0 is the default sequence.
  std::uint32_t seed = 0;
  std::string variant_file;  // user variant GLSL defining userVariant(...) (shimmer/shading/user_variant.h)
  std::string device;        // substring of the Vulkan device name
  int device_lane = 0;       // renders on other lanes dispatch beside this one (vk::ContextOptions::lane)
  std::string preview_png;   // when set: a tone-mapped PNG of frame 0's beauty
  // Khronos validation layer (when installed); anything it reports fails the
  // render. On by default in debug builds.
  bool validation = kValidationByDefault;
  // ZIP for frames people keep; none for frames measured once and deleted
  // (the experiment runner's): zlib then costs more than the rendering.
  bool compress_exr = true;
};

// Limits of RenderSettings, checked before anything is allocated.
inline constexpr int kMaxImageSide = 16384;
inline constexpr int kMaxFrames = 100000;
inline constexpr int kMaxReferenceSpp = 64;  // N of N x N
inline constexpr int kMaxRounds = 4096;

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
  int unconverged_pixels = 0;  // adaptive reference: pixels above the tolerance after max_rounds
  float at(int channel, int x, int y) const {
    return planes[std::size_t(channel) * width * height + std::size_t(y) * width + x];
  }
};

// Where a renderer's start-up went. A step done earlier in the process (the
// kernel, a pipeline another renderer made) counts 0; one found in the
// on-disk kernel cache counts the time to read it.
struct Timings {
  double compile_ms = 0;     // GLSL -> SPIR-V
  double specialize_ms = 0;  // freezing the specialization constants into the module
  double pipeline_ms = 0;    // vkCreateComputePipelines
  double jit_ms = 0;         // first (warm-up) dispatch: lavapipe's LLVM JIT
  double startup_ms = 0;     // all of Renderer::Create: from the settings to a renderer ready for frame 0
};

// Resolved from RenderSettings; describes what is rendered.
struct ResolvedVariant {
  std::string name;
  int id = 0;
  int spp_n = 1;
  bool reference = false;
  shading::Params<double> params;
  std::vector<std::pair<std::string, double>> shown_params;  // the variant's own parameters with values
  std::shared_ptr<const shading::UserVariant> user;          // set for a variant file
};

// Checks every field of `settings` that needs no device, the variant and its
// parameters included; the error names the field ("width", "reference_spp",
// a parameter), as RenderSettings spells it.
Status ValidateSettings(const RenderSettings& settings);

class Renderer {
 public:
  // Validates settings, opens the device, compiles the kernel. On failure the
  // error names the cause (no device, unknown variant, compile error with file:line, ...).
  static Result<std::unique_ptr<Renderer>> Create(const RenderSettings& settings);
  ~Renderer();

  Result<Frame> RenderFrame(int index);

  const RenderSettings& settings() const;
  const ResolvedVariant& variant() const;
  const Timings& timings() const;
  std::string device_name() const;
  std::string device_driver() const;
  bool validation_active() const;  // the validation layer was asked for and is loaded
  std::span<const glm::vec4> scene_words() const;
  shading::CameraDesc camera(int frame) const;

 private:
  Renderer();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What a render's frames are made of, known without a device. `kernel` is
// the canonical hash (shading::CanonicalSpirvHash) of the specialized kernel
// module the render runs; `inputs` hashes everything that module reads: the
// packed scene (primitives, BVH, normal-map texels), every frame's constants
// (cameras, light, material, size), every frame's push constants (variant
// parameters, replicates, seed, tolerance) and the round cap. Two settings
// with equal fingerprints render equal frames; names (of the scene, the
// variant) are not part of it.
struct RenderFingerprint {
  std::string kernel, inputs;
};
// Fails as Renderer::Create would on settings it rejects (the error names
// the field) or a kernel that does not compile.
Result<RenderFingerprint> FingerprintRender(const RenderSettings& settings);

// The static instruction counts of the kernel a render with `settings` runs
// (shading::InstructionCensus): what it costs on any device, by unit.
Result<shading::InstructionCensus> CountKernelInstructions(const RenderSettings& settings);

struct DeviceDescription {
  std::string name, driver;
  std::string type;  // "discrete", "integrated", "virtual", "cpu", "other"
  std::uint32_t subgroup_size = 0;
  bool quad_ops = false;  // subgroup quad operations in compute: quad derivatives work
};
// Every Vulkan 1.2 device with a compute queue.
Result<std::vector<DeviceDescription>> ListDevices();

// One variant's filtered NDF at one footprint, evaluated by one invocation on
// a Vulkan device, in the device's float (shaders/ndf_probe.comp): how a user
// variant, which exists only as GLSL, is evaluated as written.
struct NdfProbe {
  int variant_id = 0;                               // a catalogue id; ignored when `user` is set
  std::shared_ptr<const shading::UserVariant> user;  // a variant file, parsed
  shading::Ndf ndf = shading::Ndf::kGgx;
  glm::dvec2 alpha{0.1, 0.1};
  shading::Footprint<double> footprint;
  shading::Params<double> params;  // in the slots the kernel reads (ResolveUserParams for a file)
  std::string device;              // substring of the Vulkan device name
};
Result<shading::FilteredNdf<double>> ProbeNdf(const NdfProbe& probe);

// Compiles the render kernel with the user's file, without a device: the
// error names the file and line, as a render would.
Status CheckUserVariant(const shading::UserVariant& user);

// The source revision compiled in (git describe at configure time).
std::string SourceRevision();

// Renders settings.frames frames into out_dir (frame_NNNN.exr + sequence.json),
// writing EXR on a worker thread while the next frame renders. sequence.json
// says "status": "running" until every frame is on disk, then "complete"; any
// failure after it was first written (a frame that fails to render, a write
// error, the preview) makes it "failed" with the "error", the frames before
// it left whole. Returns what sequence.json says. `progress(done, total)`
// after each frame.
Result<SequenceFile> RenderSequence(const RenderSettings& settings, const std::string& out_dir,
                                    const std::function<void(int, int)>& progress);

// Writes a tone-mapped (x / (1 + x), sRGB) 8-bit PNG of the beauty layer.
Status WritePreviewPng(const std::string& path, const Frame& frame);

// Writes one frame as float EXR, ZIP-compressed or not.
Status WriteFrameExr(const std::string& path, const Frame& frame, bool with_stderr, bool compress = true);

}  // namespace shimmer::render
