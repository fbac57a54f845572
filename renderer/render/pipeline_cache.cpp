#include "pipeline_cache.h"

#include <cctype>
#include <chrono>
#include <map>
#include <mutex>
#include <sstream>
#include <string_view>
#include <tuple>

namespace shimmer::render {

namespace embedded {
std::span<const std::pair<std::string_view, std::string_view>> Sources();
}

namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

constexpr std::string_view kUserVariantFile = "user_variant.glsl";

// The kernel and the files it includes besides the shading core.
std::vector<shading::GlslFile> KernelFiles(bool user_variant, bool sg_light, shading::GlslFile* main) {
  std::vector<shading::GlslFile> extra;
  for (const auto& [name, body] : embedded::Sources()) {
    if (name == "render.comp")
      *main = {std::string(name), std::string(body)};
    else
      extra.push_back({std::string(name), std::string(body)});
  }
  // After #version (line 1): keep the kernel's own line numbers after the defines.
  std::string defines;
  if (user_variant) defines += "#define SHIMMER_USER_VARIANT\n";
  if (sg_light) defines += "#define SHIMMER_SG_LIGHT\n";
  if (!defines.empty()) main->text.insert(main->text.find('\n') + 1, defines + "#line 2\n");
  return extra;
}

constexpr std::string_view kUserVariantSignature =
    "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, VariantParams p)";

// A compile failure of the user's variant file as one line. glslang's log has
// a line per error ("ERROR: user_variant.glsl:2: 'x' : undeclared identifier",
// then "ERROR: 2 compilation errors. ..."); the first one says it, under the
// name the user gave the file. An error inside the kernel means the file did
// not define what the kernel calls: that is the user's file too, and the
// kernel's line numbers would mean nothing to them.
std::string UserVariantError(const std::string& log, const std::string& user_file) {
  std::vector<std::string> errors;
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("ERROR: ", 0) != 0) continue;
    line.erase(0, 7);
    if (!line.empty() && std::isdigit(static_cast<unsigned char>(line[0]))) continue;  // "N compilation errors"
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    errors.push_back(line);
  }
  if (errors.empty()) return user_file + ": does not compile as a variant";
  // "<file>:<line>: '<token>' : <problem>"; the token is often empty.
  std::string first = errors.front(), where, problem = first;
  if (auto colon = first.find(": '"); colon != std::string::npos) {
    where = first.substr(0, colon);
    problem = first.substr(colon + 2);
    if (auto sep = problem.find("' :"); sep != std::string::npos) {
      const std::string token = problem.substr(1, sep - 1);
      std::string text = problem.substr(sep + 3);
      text.erase(0, text.find_first_not_of(' '));
      problem = token.empty() ? text : "'" + token + "': " + text;
    }
  }
  const std::string more =
      errors.size() > 1 ? " (and " + std::to_string(errors.size() - 1) + " more compile errors)" : "";
  if (where.rfind(kUserVariantFile, 0) == 0)
    return user_file + where.substr(kUserVariantFile.size()) + ": " + problem + more;
  return user_file + ": does not define " + std::string(kUserVariantSignature) +
         " (the kernel's call fails: " + problem + ")";
}

struct SpirvCache {
  std::mutex mutex;
  std::map<std::string, std::shared_ptr<const shading::Spirv>> modules;
};

}  // namespace

struct PipelineSlot {
  std::once_flag compiled;
  std::shared_ptr<vk::ComputePipeline> pipeline;
  Error error;
};
using PipelineKey = std::pair<const shading::Spirv*, std::vector<std::int32_t>>;
struct DevicePipelines {
  std::mutex mutex;  // guards `slots`
  std::map<PipelineKey, std::shared_ptr<PipelineSlot>> slots;
};

namespace {

struct DeviceCache {
  std::mutex mutex;
  std::map<std::pair<std::string, bool>, DeviceHandle> devices;  // (device name, validation)
};

// Leaked on purpose, see DeviceHandle.
SpirvCache& Modules() {
  static auto* cache = new SpirvCache;
  return *cache;
}
DeviceCache& Devices() {
  static auto* cache = new DeviceCache;
  return *cache;
}

}  // namespace

Result<std::shared_ptr<const shading::Spirv>> KernelSpirv(const std::string& user_text, const std::string& user_file,
                                                          bool sg_light, double* compile_ms) {
  const bool user = !user_file.empty();
  const std::string key = std::string(sg_light ? "sg:" : "delta:") + (user ? "user:" + user_text : std::string());
  const auto t0 = Clock::now();
  std::lock_guard lock(Modules().mutex);
  if (auto it = Modules().modules.find(key); it != Modules().modules.end()) return it->second;
  shading::GlslFile main;
  std::vector<shading::GlslFile> extra = KernelFiles(user, sg_light, &main);
  if (user) extra.push_back({std::string(kUserVariantFile), user_text});
  auto compiled = shading::CompileCompute(main, extra);
  if (!compiled) {
    if (!user) return Prefixed("render.comp does not compile", compiled.failure());
    return Result<std::shared_ptr<const shading::Spirv>>::Failure(UserVariantError(compiled.error(), user_file));
  }
  auto module = std::make_shared<const shading::Spirv>(std::move(*compiled));
  Modules().modules.emplace(key, module);
  if (compile_ms) *compile_ms = MsSince(t0);
  return module;
}

Result<DeviceHandle> AcquireDevice(const vk::ContextOptions& options) {
  auto create = [&]() -> Result<DeviceHandle> {
    auto context = vk::Context::Create(options);
    if (!context) return context.failure();
    return DeviceHandle{std::shared_ptr<vk::Context>(std::move(*context)), std::make_shared<DevicePipelines>()};
  };
  if (options.lose_device_after_dispatches >= 0) return create();
  DeviceCache& cache = Devices();
  std::lock_guard lock(cache.mutex);
  DeviceHandle& entry = cache.devices[{options.device_name, options.validation}];
  if (!entry.context) {
    auto created = create();
    if (!created) return created.failure();
    entry = std::move(*created);
  }
  return entry;
}

Result<std::shared_ptr<vk::ComputePipeline>> AcquirePipeline(const DeviceHandle& device,
                                                             const std::shared_ptr<const shading::Spirv>& spirv,
                                                             std::span<const std::int32_t> specialization,
                                                             std::span<const vk::BufferKind> bindings,
                                                             std::uint32_t push_bytes, double* pipeline_ms) {
  std::shared_ptr<PipelineSlot> slot;
  {
    // The SPIR-V modules live as long as the process, so their address is a key.
    std::lock_guard lock(device.pipelines->mutex);
    auto& entry = device.pipelines->slots[{spirv.get(), {specialization.begin(), specialization.end()}}];
    if (!entry) entry = std::make_shared<PipelineSlot>();
    slot = entry;
  }
  std::call_once(slot->compiled, [&] {
    const auto t0 = Clock::now();
    auto pipeline = device.context->CreatePipeline(*spirv, specialization, bindings, push_bytes);
    if (pipeline)
      slot->pipeline = std::shared_ptr<vk::ComputePipeline>(std::move(*pipeline));
    else
      slot->error = pipeline.failure();
    if (pipeline_ms) *pipeline_ms = MsSince(t0);
  });
  if (!slot->pipeline) return slot->error;
  return slot->pipeline;
}

}  // namespace shimmer::render
