// What the kernel is given besides its module, from the settings alone: its
// specialization constants, a frame's constants and a frame's push
// constants. The renderer and FingerprintRender both build them here, so
// that a render's fingerprint hashes exactly what the render uploads.
#pragma once

#include <array>
#include <cstdint>

#include "gpu_layout.h"
#include "shimmer/renderer/renderer.h"

namespace shimmer::render {

// Whether the render is an adaptive reference (a tolerance instead of a
// fixed sample count).
bool Adaptive(const ResolvedVariant& variant, const RenderSettings& settings);

// render.comp's constant_id 0..6: variant, derivative source, spp N, scene
// features, NDF, reference, adaptive.
std::array<std::int32_t, 7> KernelSpecialization(const ResolvedVariant& variant, const RenderSettings& settings);

// Frame `index`'s camera and the one before it (motion), the light, the
// material and the image size; the band fields (size[2], size[3]) are 0.
gpu::FrameConstants FrameConstantsOf(const RenderSettings& settings, int index);

// Frame `index`'s push constants with round 0; the renderer sets the round
// of each dispatch.
gpu::Push PushOf(const ResolvedVariant& variant, const RenderSettings& settings, int index);

}  // namespace shimmer::render
