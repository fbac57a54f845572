#include "pipeline_cache.h"

#include <cctype>
#include <chrono>
#include <cstring>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <tuple>

#include "kernel_disk_cache.h"
#include "test_hooks.h"
#include "shimmer/core/content_hash.h"

namespace shimmer::render {

namespace embedded {
std::span<const std::pair<std::string_view, std::string_view>> Sources();
}

namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

constexpr std::string_view kUserVariantFile = "user_variant.glsl";
constexpr std::string_view kUserParamsFile = "user_params.glsl";  // UserParamsGlsl

// The kernel and the files it includes besides the shading core.
// Files of `overrides` (test hooks) come first: the includer takes the
// first file of a name.
std::vector<shading::GlslFile> KernelFiles(std::string_view kernel, bool user_variant, bool sg_light, bool meshes,
                                           bool counted_glints,
                                           std::span<const std::pair<std::string, std::string>> overrides,
                                           shading::GlslFile* main) {
  std::vector<shading::GlslFile> extra;
  for (const auto& [name, body] : overrides)
    if (name != kernel) extra.push_back({name, body});
  for (const auto& [name, body] : embedded::Sources()) {
    if (name == kernel)
      *main = {std::string(name), std::string(body)};
    else
      extra.push_back({std::string(name), std::string(body)});
  }
  for (const auto& [name, body] : overrides)
    if (name == kernel) main->text = body;
  // After #version (line 1): keep the kernel's own line numbers after the defines.
  std::string defines;
  if (user_variant) defines += "#define SHIMMER_USER_VARIANT\n";
  if (sg_light) defines += "#define SHIMMER_SG_LIGHT\n";
  if (meshes) defines += "#define SHIMMER_MESHES\n";
  if (counted_glints) defines += "#define SHIMMER_COUNTED_GLINTS\n";
  if (!defines.empty()) main->text.insert(main->text.find('\n') + 1, defines + "#line 2\n");
  return extra;
}

constexpr std::string_view kUserVariantSignature =
    "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p)";

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
  std::map<std::string, std::shared_ptr<const KernelModule>> modules;
};

// Each cache folder is trimmed to this once per process, before its first
// write: a specialized module is ~140 KB, a kernel ~190 KB, so this holds a
// few thousand pipelines' worth, far more than a spec uses.
constexpr std::uintmax_t kCacheFolderBytes = std::uintmax_t(256) << 20;

std::optional<std::filesystem::path> CacheFolder(std::string_view name) {
  auto root = KernelCacheDirectory();
  if (!root) return std::nullopt;
  return *root / name;
}

void WriteTrimmed(const std::filesystem::path& folder, const std::string& file, std::string_view kind,
                  std::string_view payload) {
  static std::mutex mutex;
  static auto* trimmed = new std::set<std::filesystem::path>;  // leaked, like the caches
  {
    std::lock_guard lock(mutex);
    if (trimmed->insert(folder).second) TrimCacheFolder(folder, kCacheFolderBytes);
  }
  WriteCacheFile(folder / file, kind, payload);
}

std::string_view AsBytes(const shading::Spirv& words) {
  return {reinterpret_cast<const char*>(words.data()), words.size() * sizeof(std::uint32_t)};
}

// SPIR-V words from a cache payload, or nothing (with a warning) when it is
// not a SPIR-V module.
std::optional<shading::Spirv> SpirvOf(const std::string& payload, const std::filesystem::path& file) {
  constexpr std::uint32_t kSpirvMagic = 0x07230203;
  shading::Spirv words(payload.size() / sizeof(std::uint32_t));
  std::memcpy(words.data(), payload.data(), words.size() * sizeof(std::uint32_t));
  if (payload.size() % sizeof(std::uint32_t) != 0 || words.size() < 5 || words[0] != kSpirvMagic) {
    WarnIgnoredCacheFile(file, "not a SPIR-V module");
    return std::nullopt;
  }
  return words;
}

// A module from `folder/file` when cached there, else made by `make` and
// cached. `made` says whether `make` ran.
Result<shading::Spirv> CachedSpirv(const std::optional<std::filesystem::path>& folder, const std::string& file,
                                   const std::function<Result<shading::Spirv>()>& make) {
  if (folder)
    if (auto payload = ReadCacheFile(*folder / file, "spirv"))
      if (auto words = SpirvOf(*payload, *folder / file)) return std::move(*words);
  auto made = make();
  if (made && folder) WriteTrimmed(*folder, file, "spirv", AsBytes(*made));
  return made;
}

// What names a specialized module in the cache: the kernel's sources, the
// constants and the optimizer.
std::string SpecializedKey(const KernelModule& kernel, std::span<const std::int32_t> specialization) {
  std::string constants;
  for (std::int32_t c : specialization) constants += std::to_string(c) + ",";
  return Fnv1a64Hex(kernel.key + '\0' + constants + '\0' + shading::SpecializerVersion());
}

Result<shading::Spirv> SpecializedModule(const KernelModule& kernel, std::span<const std::int32_t> specialization) {
  return CachedSpirv(CacheFolder("specialized"), SpecializedKey(kernel, specialization) + ".spv",
                     [&] { return shading::SpecializeCompute(kernel.spirv, specialization); });
}

// "alu transcendental memory control", the census as kept on disk.
std::string CensusText(const shading::InstructionCensus& c) {
  return std::to_string(c.alu) + ' ' + std::to_string(c.transcendental) + ' ' + std::to_string(c.memory) + ' ' +
         std::to_string(c.control);
}

std::optional<shading::InstructionCensus> ParseCensus(const std::string& text) {
  std::istringstream in(text);
  shading::InstructionCensus c;
  if (!(in >> c.alu >> c.transcendental >> c.memory >> c.control) || c.alu < 0 || c.transcendental < 0 ||
      c.memory < 0 || c.control < 0)
    return std::nullopt;
  return c;
}

// The canonical hash (job ids) and instruction census (the benchmark's
// device-independent cost) of a specialized kernel. Canonicalizing inlines
// the whole kernel, about 0.7 s on lavapipe's machines, and both come from
// one canonicalization; the two are kept per process and on disk, so a
// benchmark batch counts nothing the run's job ids have not already made.
Result<shading::KernelSummary> SpecializedKernelSummary(const KernelModule& kernel,
                                                        std::span<const std::int32_t> specialization) {
  static std::mutex mutex;
  static auto* summaries = new std::map<std::string, shading::KernelSummary>;  // leaked, like the caches
  const std::string key = SpecializedKey(kernel, specialization);
  {
    std::lock_guard lock(mutex);
    if (auto it = summaries->find(key); it != summaries->end()) return it->second;
  }
  const auto hashes = CacheFolder("kernel-hashes");
  const auto censuses = CacheFolder("kernel-census");
  const std::string file = Fnv1a64Hex(key + '\0' + shading::CanonicalHashVersion()) + ".txt";
  std::optional<shading::KernelSummary> summary;
  if (hashes && censuses)
    if (auto hash = ReadCacheFile(*hashes / file, "kernel-hash"); hash && hash->size() == 16)
      if (auto text = ReadCacheFile(*censuses / file, "kernel-census"))
        if (auto census = ParseCensus(*text)) summary = shading::KernelSummary{*hash, *census};
  if (!summary) {
    auto specialized = SpecializedModule(kernel, specialization);
    if (!specialized) return specialized.failure();
    auto made = shading::SummarizeKernel(*specialized);
    if (!made) return made.failure();
    summary = *made;
    if (hashes) WriteTrimmed(*hashes, file, "kernel-hash", summary->hash);
    if (censuses) WriteTrimmed(*censuses, file, "kernel-census", CensusText(summary->census));
  }
  std::lock_guard lock(mutex);
  summaries->emplace(key, *summary);
  return *summary;
}

}  // namespace

Result<std::string> SpecializedKernelHash(const KernelModule& kernel, std::span<const std::int32_t> specialization) {
  auto summary = SpecializedKernelSummary(kernel, specialization);
  if (!summary) return summary.failure();
  return summary->hash;
}

Result<shading::InstructionCensus> SpecializedKernelCensus(const KernelModule& kernel,
                                                           std::span<const std::int32_t> specialization) {
  auto summary = SpecializedKernelSummary(kernel, specialization);
  if (!summary) return summary.failure();
  return summary->census;
}

struct PipelineSlot {
  std::once_flag compiled;
  std::shared_ptr<vk::ComputePipeline> pipeline;
  Error error;
};
using PipelineKey = std::tuple<const KernelModule*, std::vector<std::int32_t>, bool>;
struct DevicePipelines {
  std::mutex mutex;  // guards `slots`
  std::map<PipelineKey, std::shared_ptr<PipelineSlot>> slots;
};

namespace {

struct DeviceCache {
  std::mutex mutex;
  std::map<std::tuple<std::string, bool, int>, DeviceHandle> devices;  // (device name, validation, lane)
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

bool CountsGlints(int variant_id) {
  for (const char* name : {"glints-zk16-counting", "glints-db23", "glints-points"})
    if (const shading::VariantInfo* info = shading::FindVariant(name); info && info->id == variant_id) return true;
  return false;
}

Result<std::shared_ptr<const KernelModule>> KernelSpirv(std::string_view kernel, const shading::UserVariant* user,
                                                        bool sg_light, bool meshes, double* compile_ms,
                                                        bool counted_glints) {
  const std::string prelude = user ? shading::UserParamsGlsl(*user) : std::string();
  const auto overrides = testing::CurrentTestHooks().source_overrides;
  std::string key = std::string(kernel) + (sg_light ? ":sg:" : ":delta:") + (meshes ? "mesh:" : "") +
                    (counted_glints ? "counted:" : "") +
                    (user ? "user:" + prelude + "\n" + user->text : std::string());
  for (const auto& [name, body] : overrides) key += '\0' + name + '\0' + body;
  const auto t0 = Clock::now();
  std::lock_guard lock(Modules().mutex);
  if (auto it = Modules().modules.find(key); it != Modules().modules.end()) return it->second;
  shading::GlslFile main;
  std::vector<shading::GlslFile> extra =
      KernelFiles(kernel, user != nullptr, sg_light, meshes, counted_glints, overrides, &main);
  if (user) {
    extra.push_back({std::string(kUserParamsFile), prelude});
    extra.push_back({std::string(kUserVariantFile), user->text});
  }
  const std::string compile_key = shading::CompileKey(main, extra);
  // Only modules that compiled are cached: a user's broken file is compiled
  // (and its error reported) every time.
  auto compiled =
      CachedSpirv(CacheFolder("spirv"), compile_key + ".spv", [&] { return shading::CompileCompute(main, extra); });
  if (!compiled) {
    if (!user) return Prefixed(std::string(kernel) + " does not compile", compiled.failure());
    return Result<std::shared_ptr<const KernelModule>>::Failure(UserVariantError(compiled.error(), user->file));
  }
  auto module = std::make_shared<const KernelModule>(KernelModule{std::move(*compiled), compile_key});
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
  DeviceHandle& entry = cache.devices[{options.device_name, options.validation, options.lane}];
  if (!entry.context) {
    auto created = create();
    if (!created) return created.failure();
    entry = std::move(*created);
  }
  return entry;
}

namespace {

// What a pipeline cache file is valid for: the driver's own identity (the
// header check in vk::Context::CreatePipelineCache) and its build.
std::string DeviceKey(const vk::DeviceInfo& d) {
  return Fnv1a64Hex(d.name + '\0' + d.driver + '\0' + std::to_string(d.vendor_id) + '\0' + std::to_string(d.device_id) +
                    '\0' + std::to_string(d.driver_version) + '\0' + d.pipeline_cache_uuid);
}

// The driver's pipeline cache seeded from disk, or an empty one when there is
// no file, the file is damaged, or the driver's header check refuses it.
Result<std::unique_ptr<vk::PipelineCache>> LoadPipelineCache(vk::Context& context,
                                                             const std::optional<std::filesystem::path>& file,
                                                             std::size_t* loaded_bytes) {
  *loaded_bytes = 0;
  if (file)
    if (auto data = ReadCacheFile(*file, "vulkan-pipeline-cache")) {
      auto seeded = context.CreatePipelineCache(*data);
      if (seeded) {
        *loaded_bytes = data->size();
        return seeded;
      }
      WarnIgnoredCacheFile(*file, seeded.error());
    }
  return context.CreatePipelineCache();
}

}  // namespace

Result<std::shared_ptr<vk::ComputePipeline>> AcquirePipeline(const DeviceHandle& device,
                                                             const std::shared_ptr<const KernelModule>& kernel,
                                                             std::span<const std::int32_t> specialization,
                                                             std::span<const vk::BufferKind> bindings,
                                                             std::uint32_t push_bytes, PipelineTimes* times,
                                                             bool driver_specializes) {
  std::shared_ptr<PipelineSlot> slot;
  {
    // The kernel modules live as long as the process, so their address is a key.
    std::lock_guard lock(device.pipelines->mutex);
    auto& entry =
        device.pipelines->slots[{kernel.get(), {specialization.begin(), specialization.end()}, driver_specializes}];
    if (!entry) entry = std::make_shared<PipelineSlot>();
    slot = entry;
  }
  std::call_once(slot->compiled, [&] {
    if (driver_specializes) {
      const auto t0 = Clock::now();
      auto pipeline = device.context->CreatePipeline(kernel->spirv, specialization, bindings, push_bytes);
      if (times) times->pipeline_ms = MsSince(t0);
      if (pipeline)
        slot->pipeline = std::shared_ptr<vk::ComputePipeline>(std::move(*pipeline));
      else
        slot->error = pipeline.failure();
      return;
    }
    const std::string key = SpecializedKey(*kernel, specialization);
    const auto t0 = Clock::now();
    auto specialized = SpecializedModule(*kernel, specialization);
    if (times) times->specialize_ms = MsSince(t0);
    if (!specialized) {
      slot->error = specialized.failure();
      return;
    }
    const auto t1 = Clock::now();
    vk::Context& context = *device.context;
    const auto folder = CacheFolder("pipelines");
    const std::string file = DeviceKey(context.device()) + "-" + key + ".bin";
    std::size_t loaded_bytes = 0;
    auto cache = LoadPipelineCache(context, folder ? std::optional(*folder / file) : std::nullopt, &loaded_bytes);
    // The constants are frozen into the module: no specialization info.
    auto pipeline = context.CreatePipeline(*specialized, {}, bindings, push_bytes, cache ? cache->get() : nullptr);
    if (times) times->pipeline_ms = MsSince(t1);
    if (!pipeline) {
      slot->error = pipeline.failure();
      return;
    }
    slot->pipeline = std::shared_ptr<vk::ComputePipeline>(std::move(*pipeline));
    // A driver that keeps nothing (lavapipe: the bare 32-byte header) gets no file.
    if (cache && folder)
      if (auto data = context.PipelineCacheData(**cache); data && data->size() > 32 && data->size() != loaded_bytes)
        WriteTrimmed(*folder, file, "vulkan-pipeline-cache", *data);
  });
  if (!slot->pipeline) return slot->error;
  return slot->pipeline;
}

}  // namespace shimmer::render
