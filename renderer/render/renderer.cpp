#include "shimmer/renderer/renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <new>
#include <sstream>

#include "gpu_layout.h"
#include "kernel_inputs.h"
#include "pipeline_cache.h"
#include "test_hooks.h"
#include "tile_lists.h"
#include "variant_resolution.h"
#include "vk.h"

namespace shimmer::render {

namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

testing::TestHooks& Hooks() {
  static testing::TestHooks hooks;
  return hooks;
}
std::mutex& HooksMutex() {
  static std::mutex m;
  return m;
}

}  // namespace

namespace testing {
ScopedTestHooks::ScopedTestHooks(const TestHooks& hooks) {
  std::lock_guard lock(HooksMutex());
  previous_ = std::exchange(Hooks(), hooks);
}
ScopedTestHooks::~ScopedTestHooks() {
  std::lock_guard lock(HooksMutex());
  Hooks() = previous_;
}
TestHooks CurrentTestHooks() {
  std::lock_guard lock(HooksMutex());
  return Hooks();
}
}  // namespace testing

std::vector<FrameChannel> FrameChannels(bool with_stderr) {
  std::vector<FrameChannel> c = {
      {"R", kBeautyR},
      {"G", kBeautyR + 1},
      {"B", kBeautyR + 2},
      {"specular.R", kSpecularR},
      {"specular.G", kSpecularR + 1},
      {"specular.B", kSpecularR + 2},
      {"diffuse.R", kDiffuseR},
      {"diffuse.G", kDiffuseR + 1},
      {"diffuse.B", kDiffuseR + 2},
      {"motion.X", kMotionX},
      {"motion.Y", kMotionX + 1},
      {"depth.Z", kDepth},
      {"normal.X", kNormalX},
      {"normal.Y", kNormalX + 1},
      {"normal.Z", kNormalX + 2},
      {"roughness.A", kRoughness},
      {"footprint.X", kFootprintX},
      {"footprint.Y", kFootprintX + 1},
  };
  if (with_stderr) c.push_back({"stderr.Y", kStderr});
  return c;
}

std::string SourceRevision() { return SHIMMER_GIT_REVISION; }

Result<std::vector<DeviceDescription>> ListDevices() {
  auto devices = vk::Context::ListDevices();
  if (!devices) return devices.failure();
  std::vector<DeviceDescription> out;
  for (const vk::DeviceInfo& d : *devices)
    out.push_back({d.name, d.driver, d.type, d.subgroup_size, d.quad_ops_in_compute});
  return out;
}

namespace {

// The checks of ValidateSettings that are not the variant's.
Status ValidateNumbers(const RenderSettings& s) {
  auto fail = [](std::string message) { return Status::Failure(std::move(message)); };
  if (s.width < 1 || s.height < 1 || s.width > kMaxImageSide || s.height > kMaxImageSide)
    return fail("width and height must be in 1.." + std::to_string(kMaxImageSide) + ", got " + std::to_string(s.width) +
                "x" + std::to_string(s.height));
  if (s.frames < 1 || s.frames > kMaxFrames)
    return fail("frames must be in 1.." + std::to_string(kMaxFrames) + ", got " + std::to_string(s.frames));
  if (!(s.fps > 0) || !std::isfinite(s.fps) || s.fps > 1e6) return fail("fps must be a number in (0, 1e6]");
  if (s.reference_spp < 0 || s.reference_spp > kMaxReferenceSpp)
    return fail("reference_spp must be in 1.." + std::to_string(kMaxReferenceSpp) + " (N x N samples), got " +
                std::to_string(s.reference_spp));
  if (s.reference_tolerance < 0 || !std::isfinite(s.reference_tolerance))
    return fail("reference_tolerance must be a finite value > 0");
  if (s.reference_replicates < 2 || s.reference_replicates > kMaxRounds)
    return fail("reference_replicates must be in 2.." + std::to_string(kMaxRounds) +
                " (independent N x N patterns per reference pixel; their spread is the standard error), got " +
                std::to_string(s.reference_replicates));
  if (s.max_rounds < 1 || s.max_rounds > kMaxRounds)
    return fail("max_rounds must be in 1.." + std::to_string(kMaxRounds) + ", got " + std::to_string(s.max_rounds));
  return Ok();
}

}  // namespace

Status ValidateSettings(const RenderSettings& s) {
  if (Status numbers = ValidateNumbers(s); !numbers) return numbers;
  if (auto v = ResolveVariant(s); !v) return v.failure();
  return Ok();
}

struct Renderer::Impl {
  RenderSettings settings;
  ResolvedVariant variant;
  Timings timings;
  std::vector<glm::vec4> words;
  std::shared_ptr<vk::Context> ctx;
  std::shared_ptr<vk::ComputePipeline> pipeline;
  std::unique_ptr<vk::Buffer> frame_buf, scene_buf, image_buf, counter_buf, tile_buf;
  int band_rows = 0;  // rows the image buffer holds
  bool walk_instead_of_tile_lists = false;  // the test hook

  // Band [y0, y0 + rows) between the image buffer (channel planes of
  // width x rows) and the frame's full-height planes.
  void CopyBand(Frame& frame, int y0, int rows, bool to_frame) const {
    const std::size_t w = std::size_t(settings.width), band = w * rows, full = w * settings.height;
    auto* buffer = static_cast<float*>(image_buf->data());
    for (int ch = 0; ch < kChannelCount; ++ch) {
      float* in_frame = frame.planes.data() + ch * full + std::size_t(y0) * w;
      float* in_buffer = buffer + ch * band;
      if (to_frame)
        std::memcpy(in_frame, in_buffer, band * sizeof(float));
      else
        std::memcpy(in_buffer, in_frame, band * sizeof(float));
    }
  }

  // `columns` x `rows` pixels in 8 x 8 workgroups.
  Status Dispatch(const gpu::Push& push, double* gpu_ms, int columns, int rows) {
    vk::Buffer* bufs[] = {frame_buf.get(), scene_buf.get(), image_buf.get(), counter_buf.get(), tile_buf.get()};
    auto bytes = std::as_bytes(std::span<const gpu::Push>(&push, 1));
    auto groups = [](int n) { return std::uint32_t((n + 7) / 8); };
    auto ms = ctx->Dispatch(*pipeline, bufs, bytes, groups(columns), groups(rows));
    if (!ms) return ms.failure();
    *gpu_ms += *ms;
    return ValidationStatus();
  }

  // The frame's tile lists (every round of a reference shares its camera),
  // or, under the test hook, every tile's count -1: the BVH walk.
  void UploadTileLists(int index) {
    const std::span<std::int32_t> out(static_cast<std::int32_t*>(tile_buf->data()),
                                      TileListWords(settings.width, settings.height));
    if (walk_instead_of_tile_lists) {
      WalkEveryTile(settings.width, settings.height, out);
      return;
    }
    BuildTileLists(words, scene::CameraAt(settings.camera, settings.scene.rig, index, settings.fps, settings.width,
                                          settings.height),
                   settings.width, settings.height, out);
  }

  // With validation on, anything the layer reported fails the render: a
  // frame computed through an invalid API use is not a result.
  Status ValidationStatus() {
    std::vector<std::string> messages = ctx->TakeValidationMessages();
    if (messages.empty()) return Ok();
    std::string more = messages.size() > 1 ? " (and " + std::to_string(messages.size() - 1) + " more)" : "";
    return Status::Failure("Vulkan validation layer: " + messages.front() + more, ErrorCode::kInternal);
  }
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}
Renderer::~Renderer() = default;
const RenderSettings& Renderer::settings() const { return impl_->settings; }
const ResolvedVariant& Renderer::variant() const { return impl_->variant; }
const Timings& Renderer::timings() const { return impl_->timings; }
std::string Renderer::device_name() const { return impl_->ctx->device().name; }
std::string Renderer::device_driver() const { return impl_->ctx->device().driver; }
bool Renderer::validation_active() const { return impl_->ctx->validation_active(); }
std::span<const glm::vec4> Renderer::scene_words() const { return impl_->words; }

shading::CameraDesc Renderer::camera(int frame) const {
  const RenderSettings& s = impl_->settings;
  return scene::CameraAt(s.camera, s.scene.rig, frame, s.fps, s.width, s.height);
}

Result<std::unique_ptr<Renderer>> Renderer::Create(const RenderSettings& settings) {
  using R = Result<std::unique_ptr<Renderer>>;
  const auto t_start = Clock::now();
  if (Status s = ValidateNumbers(settings); !s) return s.failure();
  const testing::TestHooks hooks = testing::CurrentTestHooks();
  std::unique_ptr<Renderer> r(new Renderer());
  Impl& im = *r->impl_;
  im.settings = settings;
  im.walk_instead_of_tile_lists = hooks.walk_instead_of_tile_lists;
  auto variant = ResolveVariant(settings);
  if (!variant) return variant.failure();
  im.variant = *variant;

  // Kernel source first: a compile error is reported before touching Vulkan.
  const bool sg_light = settings.scene.light.type == shading::LightType::kSg;
  const bool meshes = (scene::SceneFeatures(settings.scene) & shading::kSceneMeshes) != 0;
  auto spirv = KernelSpirv("render.comp", im.variant.user.get(), sg_light, meshes, &im.timings.compile_ms,
                           CountsGlints(im.variant.id));
  if (!spirv) return spirv.failure();

  vk::ContextOptions options;
  options.device_name = settings.device;
  options.validation = settings.validation;
  options.lane = settings.device_lane;
  options.lose_device_after_dispatches = hooks.lose_device_after_dispatches;
  auto device = AcquireDevice(options);
  if (!device) return device.failure();
  im.ctx = device->context;
  const vk::DeviceInfo& dev = im.ctx->device();
  if (im.variant.spp_n == 1 && settings.derivatives != shading::DerivativeSource::kAnalytic &&
      (!dev.quad_ops_in_compute || dev.subgroup_size < 4))
    return R::Failure("device '" + dev.name +
                      "' has no subgroup quad operations in compute shaders; use analytic derivatives");

  const auto spec = KernelSpecialization(im.variant, settings);
  using vk::BufferKind;
  const BufferKind kinds[] = {BufferKind::kUniform, BufferKind::kStorage, BufferKind::kStorage, BufferKind::kStorage,
                              BufferKind::kStorage};
  PipelineTimes pipeline_times;
  auto pipeline =
      AcquirePipeline(*device, *spirv, spec, kinds, sizeof(gpu::Push), &pipeline_times, hooks.driver_specializes);
  im.timings.specialize_ms = pipeline_times.specialize_ms;
  im.timings.pipeline_ms = pipeline_times.pipeline_ms;
  if (!pipeline) return pipeline.failure();
  im.pipeline = *pipeline;

  im.words = scene::PackScene(settings.scene);
  if (im.words.size() * sizeof(glm::vec4) > dev.max_storage_buffer_range)
    return R::Failure("the scene takes " + std::to_string((im.words.size() * sizeof(glm::vec4)) >> 20) +
                          " MiB, over the device's " + std::to_string(dev.max_storage_buffer_range >> 20) +
                          " MiB storage buffers; use smaller assets",
                      ErrorCode::kOutOfMemory);
  // Rows of all the layers that fit one storage buffer, in whole workgroups.
  const std::size_t row_bytes = std::size_t(settings.width) * kChannelCount * sizeof(float);
  const int fitting_rows = int(std::min<std::uint64_t>(dev.max_storage_buffer_range / row_bytes, 1 << 30)) / 8 * 8;
  if (hooks.band_rows < 0 || hooks.band_rows % 8 != 0)
    return R::Failure("band rows must be a positive multiple of 8 (got " + std::to_string(hooks.band_rows) + ")",
                      ErrorCode::kInternal);
  if (fitting_rows == 0)
    return R::Failure("an image " + std::to_string(settings.width) + " pixels wide does not fit the device's " +
                          std::to_string(dev.max_storage_buffer_range >> 20) +
                          " MiB storage buffers even 8 rows at a time",
                      ErrorCode::kOutOfMemory);
  im.band_rows = std::min(hooks.band_rows > 0 ? std::min(hooks.band_rows, fitting_rows) : fitting_rows,
                          (settings.height + 7) / 8 * 8);
  const std::size_t bytes[] = {sizeof(gpu::FrameConstants), im.words.size() * sizeof(glm::vec4),
                               std::size_t(im.band_rows) * row_bytes, 16,
                               TileListWords(settings.width, settings.height) * sizeof(std::int32_t)};
  std::unique_ptr<vk::Buffer>* slots[] = {&im.frame_buf, &im.scene_buf, &im.image_buf, &im.counter_buf,
                                          &im.tile_buf};
  const char* names[] = {"frame constants", "scene", "image band", "counter", "tile lists"};
  for (int i = 0; i < 5; ++i) {
    auto b = im.ctx->CreateBuffer(bytes[i], kinds[i]);
    if (!b) return Prefixed(names[i], b.failure());
    *slots[i] = std::move(*b);
  }
  std::memcpy(im.scene_buf->data(), im.words.data(), im.words.size() * sizeof(glm::vec4));

  // Warm-up: the first dispatch includes lavapipe's JIT; keep it out of frame times.
  auto t2 = Clock::now();
  gpu::FrameConstants empty{};  // size 0: every invocation is outside the image
  std::memcpy(im.frame_buf->data(), &empty, sizeof empty);
  double warm_ms = 0;
  if (Status s = im.Dispatch(gpu::Push{}, &warm_ms, 1, 1); !s) return s.failure();
  im.timings.jit_ms = MsSince(t2);
  im.timings.startup_ms = MsSince(t_start);
  return r;
}

Result<Frame> Renderer::RenderFrame(int index) {
  Impl& im = *impl_;
  const RenderSettings& s = im.settings;
  gpu::FrameConstants f = FrameConstantsOf(s, index);
  gpu::Push push = PushOf(im.variant, s, index);
  im.UploadTileLists(index);
  const bool adaptive = im.variant.reference && s.reference_tolerance > 0;
  // A reference renders K replicates (rounds), an adaptive one then more
  // until every pixel is within the tolerance or max_rounds is reached. (N = 1
  // shades the pixel centre: there is nothing to replicate.)
  const int replicates = im.variant.reference && im.variant.spp_n > 1 ? s.reference_replicates : 1;
  const int rounds = adaptive ? std::max(replicates, s.max_rounds) : replicates;
  Frame frame;
  frame.rounds = 0;
  frame.width = s.width;
  frame.height = s.height;
  try {
    frame.planes.resize(std::size_t(s.width) * s.height * kChannelCount);
  } catch (const std::bad_alloc&) {
    return Result<Frame>::Failure("out of memory for a " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                                      " frame of " + std::to_string(kChannelCount) + " float planes",
                                  ErrorCode::kOutOfMemory);
  }
  // One band unless the image outgrows a storage buffer. With several, each
  // band's planes are read back after its dispatch, and an adaptive round
  // first uploads the band's earlier rounds, which the kernel merges into.
  const bool banded = im.band_rows < s.height;
  auto band_rows = [&](int y0) { return std::min(im.band_rows, s.height - y0); };
  for (int round = 0; round < rounds; ++round) {
    push.round[0] = round;
    std::uint32_t unconverged = 0;
    for (int y0 = 0; y0 < s.height; y0 += im.band_rows) {
      const int rows = band_rows(y0);
      if (banded && round > 0) im.CopyBand(frame, y0, rows, false);
      f.size[2] = y0;
      f.size[3] = rows;
      std::memcpy(im.frame_buf->data(), &f, sizeof f);
      std::memset(im.counter_buf->data(), 0, 16);
      if (Status d = im.Dispatch(push, &frame.gpu_ms, s.width, rows); !d) return d.failure();
      std::uint32_t band_unconverged = 0;
      std::memcpy(&band_unconverged, im.counter_buf->data(), sizeof band_unconverged);
      unconverged += band_unconverged;
      if (banded) {
        auto t0 = Clock::now();
        im.CopyBand(frame, y0, rows, true);
        frame.readback_ms += MsSince(t0);
      }
    }
    frame.rounds = round + 1;
    frame.unconverged_pixels = int(unconverged);
    if (frame.rounds >= replicates && unconverged == 0) break;
  }
  if (!banded) {
    auto t0 = Clock::now();
    im.CopyBand(frame, 0, s.height, true);
    frame.readback_ms = MsSince(t0);
  }
  double total = 0;
  const std::size_t pixels = std::size_t(s.width) * s.height;
  for (std::size_t i = 0; i < pixels; ++i) total += frame.planes[kSampleCount * pixels + i];
  frame.mean_spp = total / double(pixels);
  return frame;
}

}  // namespace shimmer::render
