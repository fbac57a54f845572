// Headless Vulkan compute, in the style of vk-bootstrap: a context (instance,
// device pick, queue), host-visible storage buffers, compute pipelines and
// timed dispatches. The only code in shimmer that includes Vulkan; this
// header does not, so callers never see the boilerplate. Errors are values.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "shimmer/core/result.h"

namespace shimmer::vk {

struct DeviceInfo {
  std::string name;
  std::string driver;  // driver name and version text, e.g. "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)"
  std::string type;    // "discrete", "integrated", "virtual", "cpu", "other"
  std::uint32_t api_version = 0;
  std::uint32_t subgroup_size = 0;
  bool quad_ops_in_compute = false;
  double timestamp_period_ns = 0;  // 0: no timestamps on the compute queue
  std::uint64_t max_storage_buffer_range = 0;
  std::uint64_t max_uniform_buffer_range = 0;
  // What a pipeline cache's data is only valid for (Vulkan spec, "Pipeline
  // Cache"): the same vendor, device and pipelineCacheUUID.
  std::uint32_t vendor_id = 0;
  std::uint32_t device_id = 0;
  std::uint32_t driver_version = 0;
  std::string pipeline_cache_uuid;  // 32 hex digits
};

// How a kernel reads a buffer. Uniform buffers suit small read-only data read
// at the same address by every invocation: lavapipe loads those once per
// SIMD batch, while a storage-buffer load goes lane by lane.
enum class BufferKind { kStorage, kUniform };

struct ContextOptions {
  std::string device_name;  // substring of the device name; empty: prefer a discrete GPU
  // VK_LAYER_KHRONOS_validation when installed, with a messenger that keeps
  // its warnings and errors (Context::TakeValidationMessages).
  bool validation = false;
  // Fault injection for tests: every dispatch after this many reports
  // VK_ERROR_DEVICE_LOST, as a reset or hung GPU does; lavapipe never loses
  // its device, so the handling would otherwise go untested. -1: never.
  int lose_device_after_dispatches = -1;
  // Renders on different lanes get different devices (VkDevice, queue,
  // command buffer): their dispatches run side by side instead of one after
  // another behind one queue. On lavapipe a lone dispatch leaves a core idle
  // at its tail and between frames, so two workers each on their own lane
  // finish a run's frames sooner.
  int lane = 0;
};

// Errors carry ErrorCode::kDeviceLost or kOutOfMemory where Vulkan says so.

class Context;

class Buffer {
 public:
  ~Buffer();
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  void* data() const { return mapped_; }
  std::size_t size() const { return size_; }
  BufferKind kind() const { return kind_; }

 private:
  friend class Context;
  Buffer() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  void* mapped_ = nullptr;
  std::size_t size_ = 0;
  BufferKind kind_ = BufferKind::kStorage;
};

class ComputePipeline {
 public:
  ~ComputePipeline();
  ComputePipeline(const ComputePipeline&) = delete;
  ComputePipeline& operator=(const ComputePipeline&) = delete;

 private:
  friend class Context;
  ComputePipeline() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A VkPipelineCache: the driver's compiled pipelines as bytes that a later
// process can hand back. Pipelines created through it add to it.
class PipelineCache {
 public:
  ~PipelineCache();
  PipelineCache(const PipelineCache&) = delete;
  PipelineCache& operator=(const PipelineCache&) = delete;

 private:
  friend class Context;
  PipelineCache() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class Context {
 public:
  // Every Vulkan 1.2 device with a compute queue, as the loader lists them.
  static Result<std::vector<DeviceInfo>> ListDevices();
  static Result<std::unique_ptr<Context>> Create(const ContextOptions& options);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& device() const { return info_; }
  // Whether the validation layer was asked for and is loaded.
  bool validation_active() const;
  // The layer's warnings and errors since the last call, oldest first.
  std::vector<std::string> TakeValidationMessages();

  // A pipeline cache seeded with `data` (empty: none). Data the driver would
  // not accept, because it is truncated or was written by another vendor,
  // device or driver build (its header says which), is refused with the
  // reason, before the driver sees it: drivers need not survive bad data.
  Result<std::unique_ptr<PipelineCache>> CreatePipelineCache(std::string_view data = {});
  // The cache's contents, for CreatePipelineCache in a later process.
  Result<std::string> PipelineCacheData(const PipelineCache& cache);

  Result<std::unique_ptr<Buffer>> CreateBuffer(std::size_t bytes, BufferKind kind = BufferKind::kStorage);
  // A compute pipeline over buffers of the given kinds at bindings 0..n-1,
  // push constants of `push_bytes`, int specialization constants with ids
  // 0..k-1; through `cache` when given (the driver synchronises its use).
  Result<std::unique_ptr<ComputePipeline>> CreatePipeline(std::span<const std::uint32_t> spirv,
                                                          std::span<const std::int32_t> specialization,
                                                          std::span<const BufferKind> bindings,
                                                          std::uint32_t push_bytes, PipelineCache* cache = nullptr);
  // Records, submits and waits for one dispatch of groups_x * groups_y
  // workgroups; returns its GPU milliseconds, from timestamps around the
  // dispatch (wall time when the queue has none). Thread-safe: dispatches
  // from several threads run one at a time.
  Result<double> Dispatch(ComputePipeline& pipeline, std::span<Buffer* const> buffers, std::span<const std::byte> push,
                          std::uint32_t groups_x, std::uint32_t groups_y);

 private:
  Context() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  DeviceInfo info_;
};

}  // namespace shimmer::vk
