// The data the kernel reads and writes, as C++ sees it: the frame constants
// (render.comp FrameBuf, std140), the push constants (Push) and the channel
// planes of the image buffer (channels.glsl, included here as C++ so the
// Channel enum is built from the kernel's own numbers).
#pragma once

#include <cstddef>
#include <cstdint>

#include "shimmer/renderer/renderer.h"

namespace shimmer::render::gpu {

#include "channels.glsl"

struct Camera {
  float pos_tan[4], fwd_aspect[4], right[4], up[4];
};
struct FrameConstants {
  Camera cam, prev;
  float light_a[4], light_b[4], mat_a[4], mat_f0[4], mat_albedo[4];
  std::int32_t size[4];
};
// params and params2: shading::PackVariantParams, in the table's slot order.
struct Push {
  float params[4];
  std::int32_t round[4];
  float target[4];
  float params2[4];
};
static_assert(shading::kVariantParamCount == 8,
              "the kernels carry the variant parameters in two vec4 slots: widen Push and "
              "VARIANT_PARAMS_FROM_SLOTS's callers for more");

// std140/std430 place vec4 members at multiples of 16 bytes with no padding
// between them; these pin the C++ structs to render.comp's blocks.
static_assert(sizeof(Camera) == 64);
static_assert(offsetof(FrameConstants, prev) == 64 && offsetof(FrameConstants, light_a) == 128);
static_assert(offsetof(FrameConstants, mat_albedo) == 192 && offsetof(FrameConstants, size) == 208);
static_assert(sizeof(FrameConstants) == 224);
static_assert(offsetof(Push, round) == 16 && offsetof(Push, target) == 32 && offsetof(Push, params2) == 48 &&
              sizeof(Push) == 64);
// Push constants must fit the 128 bytes every Vulkan device guarantees.
static_assert(sizeof(Push) <= 128);

static_assert(kBeautyR == CH_BEAUTY && kSpecularR == CH_SPECULAR && kDiffuseR == CH_DIFFUSE);
static_assert(kMotionX == CH_MOTION && kDepth == CH_DEPTH && kNormalX == CH_NORMAL && kRoughness == CH_ROUGHNESS);
static_assert(kFootprintX == CH_FOOTPRINT && kStderr == CH_STDERR && kSampleCount == CH_COUNT);
static_assert(kLuminanceM2 == CH_M2 && kChannelCount == CH_PLANES);

}  // namespace shimmer::render::gpu
