// FingerprintRender: the kernel module and the bytes a render would upload,
// hashed without a device.
#include <span>
#include <string_view>

#include "kernel_inputs.h"
#include "pipeline_cache.h"
#include "shimmer/core/content_hash.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"
#include "variant_resolution.h"

namespace shimmer::render {

namespace {

template <typename T>
void Append(std::string& bytes, std::span<const T> values) {
  bytes.append(reinterpret_cast<const char*>(values.data()), values.size_bytes());
}
template <typename T>
void Append(std::string& bytes, const T& value) {
  Append(bytes, std::span<const T>(&value, 1));
}

struct ResolvedKernel {
  ResolvedVariant variant;
  std::shared_ptr<const KernelModule> module;
  std::vector<std::int32_t> specialization;
};

Result<ResolvedKernel> KernelOf(const RenderSettings& settings) {
  if (Status s = ValidateSettings(settings); !s) return s.failure();
  auto variant = ResolveVariant(settings);
  if (!variant) return variant.failure();
  const bool sg_light = settings.scene.light.type == shading::LightType::kSg;
  const bool meshes = (scene::SceneFeatures(settings.scene) & shading::kSceneMeshes) != 0;
  auto module = KernelSpirv("render.comp", variant->user.get(), sg_light, meshes, nullptr, CountsGlints(variant->id));
  if (!module) return module.failure();
  auto specialization = KernelSpecialization(*variant, settings);
  return ResolvedKernel{std::move(*variant), std::move(*module), {specialization.begin(), specialization.end()}};
}

}  // namespace

Result<shading::InstructionCensus> CountKernelInstructions(const RenderSettings& settings) {
  auto kernel = KernelOf(settings);
  if (!kernel) return kernel.failure();
  return SpecializedKernelCensus(*kernel->module, kernel->specialization);
}

Result<RenderFingerprint> FingerprintRender(const RenderSettings& settings) {
  auto resolved = KernelOf(settings);
  if (!resolved) return resolved.failure();
  const auto* variant = &resolved->variant;
  auto kernel = SpecializedKernelHash(*resolved->module, resolved->specialization);
  if (!kernel) return kernel.failure();

  // The renderer's own structs, so that a field it uploads cannot be left out.
  std::string bytes;
  const std::vector<glm::vec4> words = scene::PackScene(settings.scene);
  Append(bytes, std::span<const glm::vec4>(words));
  // The packed words hold a mesh's geometry; its material and textures are
  // in the asset's files, which the content hash covers. (Nothing is added
  // for a scene without meshes: its fingerprint is what it was.)
  for (const scene::Primitive& p : settings.scene.primitives)
    if (p.mesh) bytes += "asset:" + p.mesh->content_hash;
  for (int i = 0; i < settings.frames; ++i) {
    Append(bytes, FrameConstantsOf(settings, i));
    Append(bytes, PushOf(*variant, settings, i));
  }
  // How many rounds a reference pixel may take (the replicates ride in the push constants).
  const bool adaptive = variant->reference && settings.reference_tolerance > 0;
  Append(bytes, adaptive ? settings.max_rounds : 0);
  return RenderFingerprint{*kernel, Fnv1a64Hex(bytes)};
}

}  // namespace shimmer::render
