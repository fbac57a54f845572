// What the renderers of one process share: the kernel's SPIR-V per variant
// text, and Vulkan devices with their compiled compute pipelines. Creating a
// pipeline is where lavapipe runs LLVM (350-800 ms), most of a short
// experiment job, and jobs that differ only in parameters (push constants) or
// material values compile the same pipeline.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "shimmer/core/result.h"
#include "spirv_compiler.h"
#include "vk.h"

namespace shimmer::render {

// render.comp compiled once per process for the built-in variants (empty
// `user_text`), or once per distinct user variant text, each with or
// without the SG-light integral (`sg_light`: the scene has an SG light).
// `user_file` names the user's file in compile errors. `compile_ms` is set
// when this call compiled (0 when cached).
Result<std::shared_ptr<const shading::Spirv>> KernelSpirv(const std::string& user_text, const std::string& user_file,
                                                          bool sg_light, double* compile_ms);

// A device shared by every renderer asking for the same options, created on
// first use and never destroyed: tearing Vulkan down from static destructors
// would race the driver's own teardown, and the OS reclaims everything at
// exit. A device with injected faults is always private.
struct DevicePipelines;  // the device's compiled pipelines
struct DeviceHandle {
  std::shared_ptr<vk::Context> context;
  std::shared_ptr<DevicePipelines> pipelines;
};
Result<DeviceHandle> AcquireDevice(const vk::ContextOptions& options);

// The pipeline of `spirv` with `specialization` on `device`, compiled by the
// first renderer that needs it while others needing it wait; renderers
// needing other pipelines go on meanwhile. `pipeline_ms` is set by the call
// that compiled.
Result<std::shared_ptr<vk::ComputePipeline>> AcquirePipeline(const DeviceHandle& device,
                                                             const std::shared_ptr<const shading::Spirv>& spirv,
                                                             std::span<const std::int32_t> specialization,
                                                             std::span<const vk::BufferKind> bindings,
                                                             std::uint32_t push_bytes, double* pipeline_ms);

}  // namespace shimmer::render
