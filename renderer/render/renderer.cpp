#include "renderer.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfThreading.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "spirv_compiler.h"
#include "vk.h"

namespace shimmer::render {

namespace embedded {
std::span<const std::pair<std::string_view, std::string_view>> Sources();
}

namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// The kernel's storage buffer 0 (std430; render.comp FrameBuf).
struct GpuCamera {
  float pos_tan[4], fwd_aspect[4], right[4], up[4];
};
struct GpuFrame {
  GpuCamera cam, prev;
  float light_a[4], light_b[4], mat_a[4], mat_f0[4], mat_albedo[4];
  std::int32_t size[4];
};
struct GpuPush {
  float params[4];
  std::int32_t round[4];
  float target[4];
};

GpuCamera ToGpu(const shading::CameraDesc& c) {
  auto f = [](float* out, glm::dvec3 v, double w) {
    out[0] = float(v.x), out[1] = float(v.y), out[2] = float(v.z), out[3] = float(w);
  };
  GpuCamera g;
  f(g.pos_tan, c.pos, c.tan_half_fov_y);
  f(g.fwd_aspect, c.fwd, double(c.width) / double(c.height));
  f(g.right, c.right, 0);
  f(g.up, c.up, 0);
  return g;
}

// SPIR-V per user-variant text, for the life of the process: built-in
// variants differ only in specialization constants and share one module.
struct SpirvCache {
  std::mutex mutex;
  std::map<std::string, std::vector<std::uint32_t>> modules;
};
SpirvCache& Cache() {
  static SpirvCache cache;
  return cache;
}

// Vulkan devices and compute pipelines shared by the renderers of a process.
// Creating a pipeline is where lavapipe runs LLVM (350-800 ms), most of a
// short experiment job, and jobs that differ only in parameters (push
// constants) or material values compile the same pipeline. Never destroyed:
// tearing Vulkan down from static destructors would race the driver's own
// teardown, and the OS reclaims everything at exit.
// One pipeline, compiled by the first renderer that needs it while the others
// that need it wait; renderers needing other pipelines go on meanwhile.
struct PipelineSlot {
  std::once_flag compiled;
  std::shared_ptr<vk::ComputePipeline> pipeline;
  std::string error;
};
struct SharedDevice {
  std::shared_ptr<vk::Context> ctx;
  std::map<std::pair<std::string, std::vector<std::int32_t>>, std::shared_ptr<PipelineSlot>> pipelines;
};
struct DeviceCache {
  std::mutex mutex;
  std::map<std::pair<std::string, bool>, SharedDevice> devices;  // (device name, validation)
};
DeviceCache& Devices() {
  static auto* cache = new DeviceCache;
  return *cache;
}

std::string KernelText(bool user_variant) {
  std::string text;
  for (const auto& [name, body] : embedded::Sources())
    if (name == "render.comp") text = std::string(body);
  if (user_variant) {
    // After #version (line 1): keep the kernel's own line numbers after the define.
    auto eol = text.find('\n');
    text.insert(eol + 1, "#define SHIMMER_USER_VARIANT\n#line 2\n");
  }
  return text;
}

std::string ReadFile(const std::string& path, bool* ok) {
  std::ifstream in(path);
  *ok = static_cast<bool>(in);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::pair<ResolvedVariant, std::string> ResolveVariant(const RenderSettings& s) {
  ResolvedVariant v;
  if (s.reference_spp < 0 || s.reference_spp > 64) return {v, "--reference-spp must be in 1..64 (N x N samples)"};
  if (s.reference_tolerance < 0 || !std::isfinite(s.reference_tolerance))
    return {v, "--reference-tolerance must be a finite value > 0"};
  bool reference = s.reference_spp > 0 || s.reference_tolerance > 0;
  if (!s.variant_file.empty()) {
    if (reference) return {v, "a reference renders variant none; drop --variant-file"};
    v.name = "user:" + std::filesystem::path(s.variant_file).filename().string();
    v.id = 0;
    for (const auto& [k, x] : s.param_overrides) {
      if (k == "fp_max") v.params.fp_max = x;
      else if (k == "fp_min_cap") v.params.fp_min_cap = x;
      else if (k == "sigma2") v.params.sigma2 = x;
      else if (k == "kappa") v.params.kappa = x;
      else return {v, "a user variant takes the parameters fp_max, fp_min_cap, sigma2, kappa; got '" + k + "'"};
      v.shown_params.push_back({k, x});
    }
    return {v, ""};
  }
  std::string name = s.variant;
  int spp_n = 1;
  if (name.rfind("supersample-", 0) == 0) {
    std::string n = name.substr(12);
    std::size_t used = 0;
    try {
      spp_n = std::stoi(n, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != n.size() || spp_n < 1 || spp_n > 64)
      return {v, "variant '" + name + "': supersample-N needs N in 1..64"};
    if (reference) return {v, "a reference is already supersampled; use --variant none with --reference-spp"};
    name = "none";
  }
  const shading::VariantInfo* info = shading::FindVariant(name);
  if (!info) return {v, "unknown variant '" + s.variant + "' (see `shimmer variants`, or supersample-N)"};
  if (reference && info->id != 0) return {v, "a reference renders variant none, not " + s.variant};
  if (info->ggx_only && s.material.ndf != shading::Ndf::kGgx)
    return {v, "variant " + s.variant + " filters GGX only; use a ggx material"};
  shading::ResolvedParams rp = shading::ResolveParams(*info, s.param_overrides);
  if (!rp.error.empty()) return {v, rp.error};
  v.name = s.variant;
  v.id = info->id;
  v.params = rp.values;
  for (const shading::ParamInfo& p : info->params) {
    double x = p.name == "fp_max" ? rp.values.fp_max
               : p.name == "fp_min_cap" ? rp.values.fp_min_cap
               : p.name == "sigma2" ? rp.values.sigma2
                                     : rp.values.kappa;
    v.shown_params.push_back({std::string(p.name), x});
  }
  v.reference = reference;
  v.spp_n = reference ? (s.reference_spp > 0 ? s.reference_spp : 4) : spp_n;
  return {v, ""};
}

}  // namespace

std::vector<ExrChannel> ExrChannels(bool with_stderr) {
  std::vector<ExrChannel> c = {
      {"R", kBeautyR},          {"G", kBeautyR + 1},          {"B", kBeautyR + 2},
      {"specular.R", kSpecularR}, {"specular.G", kSpecularR + 1}, {"specular.B", kSpecularR + 2},
      {"diffuse.R", kDiffuseR},   {"diffuse.G", kDiffuseR + 1},   {"diffuse.B", kDiffuseR + 2},
      {"motion.X", kMotionX},     {"motion.Y", kMotionX + 1},     {"depth.Z", kDepth},
      {"normal.X", kNormalX},     {"normal.Y", kNormalX + 1},     {"normal.Z", kNormalX + 2},
      {"roughness.A", kRoughness}, {"footprint.X", kFootprintX},  {"footprint.Y", kFootprintX + 1},
  };
  if (with_stderr) c.push_back({"stderr.Y", kStderr});
  return c;
}

std::string SourceRevision() { return SHIMMER_GIT_REVISION; }

struct Renderer::Impl {
  RenderSettings settings;
  ResolvedVariant variant;
  Timings timings;
  std::vector<glm::vec4> words;
  std::shared_ptr<vk::Context> ctx;
  std::shared_ptr<vk::ComputePipeline> pipeline;
  std::unique_ptr<vk::Buffer> frame_buf, scene_buf, image_buf, counter_buf;
  int band_rows = 0;  // rows the image buffer holds

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
  std::string Dispatch(const GpuPush& push, double* gpu_ms, int columns, int rows) {
    vk::Buffer* bufs[] = {frame_buf.get(), scene_buf.get(), image_buf.get(), counter_buf.get()};
    auto bytes = std::as_bytes(std::span<const GpuPush>(&push, 1));
    auto groups = [](int n) { return std::uint32_t((n + 7) / 8); };
    vk::DispatchResult r = ctx->Dispatch(*pipeline, bufs, bytes, groups(columns), groups(rows));
    *gpu_ms += r.gpu_ms;
    if (!r.error.empty()) return r.error;
    return ValidationError();
  }

  // With validation on, anything the layer reported fails the render: a
  // frame computed through an invalid API use is not a result.
  std::string ValidationError() {
    std::vector<std::string> messages = ctx->TakeValidationMessages();
    if (messages.empty()) return "";
    std::string more = messages.size() > 1 ? " (and " + std::to_string(messages.size() - 1) + " more)" : "";
    return "Vulkan validation layer: " + messages.front() + more;
  }
};

Renderer::Renderer() : impl_(std::make_unique<Impl>()) {}
Renderer::~Renderer() = default;
const RenderSettings& Renderer::settings() const { return impl_->settings; }
const ResolvedVariant& Renderer::variant() const { return impl_->variant; }
const Timings& Renderer::timings() const { return impl_->timings; }
std::string Renderer::device_name() const { return impl_->ctx->device().name; }
bool Renderer::validation_active() const { return impl_->ctx->validation_active(); }
std::span<const glm::vec4> Renderer::scene_words() const { return impl_->words; }

shading::CameraDesc Renderer::camera(int frame) const {
  const RenderSettings& s = impl_->settings;
  return scene::CameraAt(s.camera, s.scene.rig, frame, s.fps, s.width, s.height);
}

std::pair<std::unique_ptr<Renderer>, std::string> Renderer::Create(const RenderSettings& settings) {
  using Out = std::pair<std::unique_ptr<Renderer>, std::string>;
  std::unique_ptr<Renderer> r(new Renderer());
  Impl& im = *r->impl_;
  im.settings = settings;
  if (settings.width < 1 || settings.height < 1 || settings.width > 16384 || settings.height > 16384)
    return Out{nullptr, "--size must be two values in 1..16384"};
  if (settings.frames < 1) return Out{nullptr, "--frames must be >= 1"};
  if (!(settings.fps > 0) || !std::isfinite(settings.fps)) return Out{nullptr, "--fps must be > 0"};
  if (!scene::IsCameraPath(settings.camera)) {
    std::string list;
    for (auto n : scene::CameraPathNames()) list += (list.empty() ? "" : ", ") + std::string(n);
    return Out{nullptr, "unknown camera path '" + settings.camera + "' (" + list + ")"};
  }
  auto [variant, verr] = ResolveVariant(settings);
  if (!verr.empty()) return Out{nullptr, verr};
  im.variant = variant;

  // Kernel source first: a compile error is reported before touching Vulkan.
  std::string user_text;
  std::vector<shading::GlslFile> extra;
  if (!settings.variant_file.empty()) {
    bool ok = false;
    user_text = ReadFile(settings.variant_file, &ok);
    if (!ok) return Out{nullptr, "cannot read variant file '" + settings.variant_file + "'"};
    extra.push_back({"user_variant.glsl", user_text});
  }
  std::vector<std::uint32_t> spirv;
  const std::string key = settings.variant_file.empty() ? std::string() : "user:" + user_text;
  {
    auto t0 = Clock::now();
    std::lock_guard<std::mutex> lock(Cache().mutex);
    auto it = Cache().modules.find(key);
    if (it == Cache().modules.end()) {
      shading::SpirvResult compiled = shading::CompileCompute({"render.comp", KernelText(!extra.empty())}, extra);
      if (!compiled.ok()) {
        std::string log = compiled.error;
        // Name the user's file as the user gave it.
        for (std::size_t p = 0; (p = log.find("user_variant.glsl", p)) != std::string::npos;) {
          log.replace(p, 17, settings.variant_file);
          p += settings.variant_file.size();
        }
        return Out{nullptr, "shader compile failed:\n" + log};
      }
      it = Cache().modules.emplace(key, std::move(compiled.words)).first;
      im.timings.compile_ms = MsSince(t0);
    }
    spirv = it->second;
  }

  vk::ContextOptions options;
  options.device_name = settings.device;
  options.validation = settings.validation;
  options.lose_device_after_dispatches = settings.lose_device_after_dispatches;
  // A device with an injected loss is this renderer's alone.
  const bool shared = settings.lose_device_after_dispatches < 0;
  std::unique_lock<std::mutex> devices_lock(Devices().mutex, std::defer_lock);
  SharedDevice private_device;
  SharedDevice* device = &private_device;
  if (shared) {
    devices_lock.lock();
    device = &Devices().devices[{settings.device, settings.validation}];
  }
  if (!device->ctx) {
    vk::Expected<vk::Context> ctx = vk::Context::Create(options);
    if (!ctx) return Out{nullptr, ctx.error};
    device->ctx = std::move(ctx.value);
  }
  im.ctx = device->ctx;
  const vk::DeviceInfo& dev = im.ctx->device();
  if (variant.spp_n == 1 && settings.derivatives != shading::DerivativeSource::kAnalytic &&
      (!dev.quad_ops_in_compute || dev.subgroup_size < 4))
    return Out{nullptr, "device '" + dev.name +
                            "' has no subgroup quad operations in compute shaders; use --derivatives analytic"};

  const std::int32_t spec[] = {variant.id, static_cast<std::int32_t>(settings.derivatives), variant.spp_n,
                               scene::SceneFeatures(settings.scene), static_cast<std::int32_t>(settings.material.ndf)};
  auto t1 = Clock::now();
  using vk::BufferKind;
  const BufferKind kinds[] = {BufferKind::kUniform, BufferKind::kStorage, BufferKind::kStorage, BufferKind::kStorage};
  std::shared_ptr<PipelineSlot>& entry =
      device->pipelines[{key, std::vector<std::int32_t>(std::begin(spec), std::end(spec))}];
  if (!entry) entry = std::make_shared<PipelineSlot>();
  const std::shared_ptr<PipelineSlot> slot = entry;
  if (devices_lock.owns_lock()) devices_lock.unlock();
  std::call_once(slot->compiled, [&] {
    auto pipe = im.ctx->CreatePipeline(spirv, spec, kinds, sizeof(GpuPush));
    slot->error = pipe.error;
    slot->pipeline = std::move(pipe.value);
    im.timings.pipeline_ms = MsSince(t1);
  });
  if (!slot->pipeline) return Out{nullptr, slot->error};
  im.pipeline = slot->pipeline;

  im.words = scene::PackScene(settings.scene);
  // Rows of all the layers that fit one storage buffer, in whole workgroups.
  const std::size_t row_bytes = std::size_t(settings.width) * kChannelCount * sizeof(float);
  const int fitting_rows = int(std::min<std::uint64_t>(dev.max_storage_buffer_range / row_bytes, 1 << 30)) / 8 * 8;
  if (settings.band_rows < 0 || settings.band_rows % 8 != 0)
    return Out{nullptr, "band rows must be a positive multiple of 8 (got " + std::to_string(settings.band_rows) + ")"};
  if (fitting_rows == 0)
    return Out{nullptr, "an image " + std::to_string(settings.width) + " pixels wide does not fit the device's " +
                            std::to_string(dev.max_storage_buffer_range >> 20) +
                            " MiB storage buffers even 8 rows at a time"};
  im.band_rows = std::min(settings.band_rows > 0 ? std::min(settings.band_rows, fitting_rows) : fitting_rows,
                          (settings.height + 7) / 8 * 8);
  const std::size_t bytes[] = {sizeof(GpuFrame), im.words.size() * sizeof(glm::vec4),
                               std::size_t(im.band_rows) * row_bytes, 16};
  std::unique_ptr<vk::Buffer>* slots[] = {&im.frame_buf, &im.scene_buf, &im.image_buf, &im.counter_buf};
  const char* names[] = {"frame constants", "scene", "image band", "counter"};
  for (int i = 0; i < 4; ++i) {
    auto b = im.ctx->CreateBuffer(bytes[i], kinds[i]);
    if (!b) return Out{nullptr, std::string(names[i]) + ": " + b.error};
    *slots[i] = std::move(b.value);
  }
  std::memcpy(im.scene_buf->data(), im.words.data(), im.words.size() * sizeof(glm::vec4));

  // Warm-up: the first dispatch includes lavapipe's JIT; keep it out of frame times.
  auto t2 = Clock::now();
  GpuFrame empty{};  // size 0: every invocation is outside the image
  std::memcpy(im.frame_buf->data(), &empty, sizeof empty);
  double warm_ms = 0;
  if (std::string e = im.Dispatch(GpuPush{}, &warm_ms, 1, 1); !e.empty()) return Out{nullptr, e};
  im.timings.jit_ms = MsSince(t2);
  return Out{std::move(r), ""};
}

Renderer::Result Renderer::RenderFrame(int index) {
  Impl& im = *impl_;
  const RenderSettings& s = im.settings;
  Result result;
  GpuFrame f{};
  f.cam = ToGpu(camera(index));
  f.prev = ToGpu(camera(index - 1));
  const shading::LightDesc& l = s.scene.light;
  auto put = [](float* out, glm::dvec3 v, double w) {
    out[0] = float(v.x), out[1] = float(v.y), out[2] = float(v.z), out[3] = float(w);
  };
  put(f.light_a, l.vec, double(static_cast<int>(l.type)));
  put(f.light_b, l.radiance, l.radius);
  put(f.mat_a, {s.material.alpha.x, s.material.alpha.y, 0.0}, 0);  // the NDF is specialization constant 4
  put(f.mat_f0, s.material.f0, 0);
  put(f.mat_albedo, s.material.albedo, 0);
  f.size[0] = s.width;
  f.size[1] = s.height;

  GpuPush push{};
  const auto& p = im.variant.params;
  push.params[0] = float(p.fp_max), push.params[1] = float(p.fp_min_cap);
  push.params[2] = float(p.sigma2), push.params[3] = float(p.kappa);
  push.round[1] = index;
  const bool adaptive = im.variant.reference && s.reference_tolerance > 0;
  push.target[0] = adaptive ? float(s.reference_tolerance) : 0.0f;
  push.target[1] = float(kReferenceLuminanceFloor);
  const int rounds = adaptive ? std::max(1, s.max_rounds) : 1;
  Frame& frame = result.frame;
  frame.rounds = 0;
  frame.width = s.width;
  frame.height = s.height;
  frame.planes.resize(std::size_t(s.width) * s.height * kChannelCount);
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
      result.error = im.Dispatch(push, &frame.gpu_ms, s.width, rows);
      if (!result.error.empty()) return result;
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
    if (unconverged == 0) break;
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
  return result;
}

std::string WriteExr(const std::string& path, const Frame& frame, bool with_stderr, bool compress) {
  // ZIP-compressing the 16-line blocks is most of a frame's write: OpenEXR
  // compresses them on its thread pool when it has one.
  static std::once_flag pool;
  std::call_once(pool, [] {
    Imf::setGlobalThreadCount(static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  });
  const std::string tmp = path + ".tmp";
  try {
    Imf::Header header(frame.width, frame.height);
    header.compression() = compress ? Imf::ZIP_COMPRESSION : Imf::NO_COMPRESSION;
    Imf::FrameBuffer fb;
    const std::size_t plane = std::size_t(frame.width) * frame.height;
    for (const ExrChannel& c : ExrChannels(with_stderr)) {
      header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
      char* base = reinterpret_cast<char*>(const_cast<float*>(frame.planes.data() + c.plane * plane));
      fb.insert(c.name, Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * frame.width));
    }
    Imf::OutputFile out(tmp.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(frame.height);
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    return "cannot write " + path + ": " + e.what();
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return "cannot write " + path + ": " + ec.message();
  }
  return "";
}

std::string WritePreviewPng(const std::string& path, const Frame& frame) {
  cv::Mat img(frame.height, frame.width, CV_8UC3);
  const std::size_t plane = std::size_t(frame.width) * frame.height;
  auto encode = [](float x) {
    double v = std::max(0.0, double(x));
    v = v / (1.0 + v);
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
    return cv::saturate_cast<unsigned char>(v * 255.0 + 0.5);
  };
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      std::size_t i = std::size_t(y) * frame.width + x;
      img.at<cv::Vec3b>(y, x) = {encode(frame.planes[(kBeautyR + 2) * plane + i]),
                                 encode(frame.planes[(kBeautyR + 1) * plane + i]),
                                 encode(frame.planes[kBeautyR * plane + i])};
    }
  try {
    if (!cv::imwrite(path, img)) return "cannot write " + path;
  } catch (const cv::Exception& e) {
    return "cannot write " + path + ": " + e.what();
  }
  return "";
}

namespace {

std::string WriteJsonAtomically(const std::string& path, const nlohmann::json& j) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) return "cannot write " + path + " (is the output directory writable?)";
    out << j.dump(2) << "\n";
    if (!out) return "cannot write " + path;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) return "cannot write " + path + ": " + ec.message();
  return "";
}

// EXR writing on a worker thread, at most two frames queued.
class FrameWriter {
 public:
  FrameWriter(bool with_stderr, bool compress)
      : with_stderr_(with_stderr), compress_(compress), thread_([this] { Loop(); }) {}
  ~FrameWriter() { Finish(); }

  void Push(std::string path, Frame frame) {
    std::unique_lock<std::mutex> lock(mutex_);
    space_.wait(lock, [this] { return queue_.size() < 2; });
    queue_.push_back({std::move(path), std::move(frame)});
    ready_.notify_one();
  }
  // Waits for every queued frame; returns the first error.
  std::string Finish() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
      ready_.notify_one();
    }
    if (thread_.joinable()) thread_.join();
    return error_;
  }
  double write_ms() const { return write_ms_; }

 private:
  void Loop() {
    for (;;) {
      std::pair<std::string, Frame> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [this] { return done_ || !queue_.empty(); });
        if (queue_.empty()) return;
        job = std::move(queue_.front());
        queue_.pop_front();
        space_.notify_one();
      }
      auto t0 = Clock::now();
      std::string e = error_.empty() ? WriteExr(job.first, job.second, with_stderr_, compress_) : "";
      write_ms_ += MsSince(t0);
      if (!e.empty() && error_.empty()) error_ = e;
    }
  }

  bool with_stderr_;
  bool compress_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<std::pair<std::string, Frame>> queue_;
  bool done_ = false;
  std::string error_;
  double write_ms_ = 0;
  std::thread thread_;
};

std::string FrameName(int i) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04d.exr", i);
  return name;
}

}  // namespace

std::string RenderSequence(const RenderSettings& settings, const std::string& out_dir,
                           const std::function<void(int, int)>& progress) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir))
    return "cannot create output directory '" + out_dir + "'" + (ec ? ": " + ec.message() : "");
  const std::string seq_path = (fs::path(out_dir) / "sequence.json").string();
  // Fail on an unwritable directory before any rendering.
  {
    std::string e = WriteJsonAtomically(seq_path + ".probe", nlohmann::json::object());
    fs::remove(seq_path + ".probe", ec);
    if (!e.empty()) return "output directory '" + out_dir + "' is not writable";
  }
  auto [renderer, error] = Renderer::Create(settings);
  if (!renderer) return error;
  const ResolvedVariant& v = renderer->variant();

  nlohmann::json params = nlohmann::json::object();
  for (const auto& [k, x] : v.shown_params) params[k] = x;
  const auto& rig = settings.scene.rig;
  static const char* kDerivNames[] = {"analytic", "quad-fine", "quad-coarse"};
  nlohmann::json seq = {
      {"status", "running"},
      {"scene", settings.scene.name},
      {"material", scene::MaterialSpec(settings.material)},
      {"light", settings.scene.light.type == shading::LightType::kDirectional ? "directional" : "sphere"},
      {"camera",
       {{"path", settings.camera},
        {"target", {rig.target.x, rig.target.y, rig.target.z}},
        {"distance", rig.distance},
        {"elevation_deg", rig.elevation_deg},
        {"azimuth_deg", rig.azimuth_deg},
        {"fov_y_deg", rig.fov_y_deg}}},
      {"variant", v.name},
      {"params", params},
      {"derivatives", v.spp_n > 1 ? "analytic" : kDerivNames[static_cast<int>(settings.derivatives)]},
      {"width", settings.width},
      {"height", settings.height},
      {"fps", settings.fps},
      {"frame_count", settings.frames},
      {"spp", v.spp_n * v.spp_n},
      {"reference", v.reference},
      {"device", renderer->device_name()},
      {"revision", SourceRevision()},
      {"timings_ms",
       {{"shader_compile", renderer->timings().compile_ms},
        {"pipeline_create", renderer->timings().pipeline_ms},
        {"first_dispatch_jit", renderer->timings().jit_ms}}},
      {"frames", nlohmann::json::array()},
  };
  if (v.reference) {
    seq["reference_spp"] = v.spp_n;
    seq["reference_tolerance"] = settings.reference_tolerance;
    seq["reference_luminance_floor"] = kReferenceLuminanceFloor;
  }
  if (!settings.variant_file.empty()) seq["variant_file"] = settings.variant_file;
  if (std::string e = WriteJsonAtomically(seq_path, seq); !e.empty()) return e;

  FrameWriter writer(v.reference, settings.compress_exr);
  double render_ms = 0, readback_ms = 0;
  for (int i = 0; i < settings.frames; ++i) {
    auto t0 = Clock::now();
    Renderer::Result r = renderer->RenderFrame(i);
    render_ms += MsSince(t0);
    if (!r.error.empty()) {
      // Frames already handed to the writer are whole; this one never gets a file.
      writer.Finish();
      const std::string error = "frame " + std::to_string(i) + ": " + r.error;
      seq["status"] = "failed";
      seq["error"] = error;
      WriteJsonAtomically(seq_path, seq);
      return error;
    }
    readback_ms += r.frame.readback_ms;
    nlohmann::json fj = {{"file", FrameName(i)}, {"gpu_ms", r.frame.gpu_ms}, {"time_s", i / settings.fps}};
    if (v.reference) {
      fj["mean_spp"] = r.frame.mean_spp;
      fj["rounds"] = r.frame.rounds;
    }
    seq["frames"].push_back(fj);
    if (i == 0 && !settings.preview_png.empty()) {
      if (std::string e = WritePreviewPng(settings.preview_png, r.frame); !e.empty()) {
        writer.Finish();
        return e;
      }
    }
    writer.Push((fs::path(out_dir) / FrameName(i)).string(), std::move(r.frame));
    if (progress) progress(i + 1, settings.frames);
  }
  if (std::string e = writer.Finish(); !e.empty()) return e;
  seq["status"] = "complete";
  seq["timings_ms"]["render_wall"] = render_ms;
  seq["timings_ms"]["readback"] = readback_ms;
  seq["timings_ms"]["exr_write"] = writer.write_ms();
  return WriteJsonAtomically(seq_path, seq);
}

}  // namespace shimmer::render
