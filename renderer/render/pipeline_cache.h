// What the renderers of one process share, and what later processes find on
// disk (kernel_disk_cache.h): the kernel's SPIR-V per variant text, its
// specialization per pipeline, and Vulkan devices with their compiled compute
// pipelines. Pipeline creation is most of a short job's start-up (lavapipe:
// SPIR-V -> NIR -> LLVM), and jobs that differ only in parameters (push
// constants) or material values use the same pipeline.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/shading/user_variant.h"
#include "shimmer/shading/spirv_compiler.h"
#include "vk.h"

namespace shimmer::render {

// A kernel of renderer/shaders (render.comp, ndf_probe.comp) compiled once
// per process for the built-in variants (`user` null), or once per distinct
// user variant text, each with or without the
// SG-light integral (`sg_light`: the scene has an SG light) and with or
// without the mesh code (`meshes`: the scene has a mesh; scene.glsl's
// SHIMMER_MESHES, so that no other kernel's SPIR-V changes). Compile errors
// name the user's file as they gave it. `compile_ms` is set when this call
// compiled (0 when cached).
struct KernelModule {
  shading::Spirv spirv;
  std::string key;  // shading::CompileKey of its sources
};
Result<std::shared_ptr<const KernelModule>> KernelSpirv(std::string_view kernel, const shading::UserVariant* user,
                                                        bool sg_light, bool meshes, double* compile_ms,
                                                        bool counted_glints = false);

// Whether the variant is one of the glint variants that count the
// footprint's microdetails (glints-zk16-counting, glints-db23, glints-points): their kernel
// is compiled with SHIMMER_COUNTED_GLINTS (glints.glsl). Every other kernel
// leaves their dispatch out, so that adding them left its SPIR-V, and the
// job ids built on it, as they were.
bool CountsGlints(int variant_id);

// shading::CanonicalSpirvHash of `kernel` specialized to `specialization`
// (the module AcquirePipeline hands the driver), kept per process; the
// specialized module comes from the disk cache when it is there.
Result<std::string> SpecializedKernelHash(const KernelModule& kernel, std::span<const std::int32_t> specialization);

// shading::CountInstructions of the same specialized module, kept beside
// its hash (one canonicalization makes both).
Result<shading::InstructionCensus> SpecializedKernelCensus(const KernelModule& kernel,
                                                           std::span<const std::int32_t> specialization);

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

// The pipeline of `kernel` with `specialization` on `device`, made by the
// first renderer that needs it while others needing it wait; renderers
// needing other pipelines go on meanwhile. The module is specialized before
// the driver sees it (shading::SpecializeCompute); the specialized module,
// and the driver's pipeline cache where it keeps one (lavapipe does not),
// are kept on disk. The call that made the pipeline sets the times.
struct PipelineTimes {
  double specialize_ms = 0;  // specializing, or reading the specialized module from disk
  double pipeline_ms = 0;    // vkCreateComputePipelines
};
Result<std::shared_ptr<vk::ComputePipeline>> AcquirePipeline(const DeviceHandle& device,
                                                             const std::shared_ptr<const KernelModule>& kernel,
                                                             std::span<const std::int32_t> specialization,
                                                             std::span<const vk::BufferKind> bindings,
                                                             std::uint32_t push_bytes, PipelineTimes* times,
                                                             bool driver_specializes = false);

}  // namespace shimmer::render
