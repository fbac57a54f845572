// The kernel's specialization constants (kernel_inputs.h): only an adaptive
// reference's kernel holds the tile rule's barrier (render.comp, ADAPTIVE).
// llvmpipe runs a workgroup whose code holds a barrier as coroutines, reached
// or not, which cost the fixed references and supersample-N about 11 %
// (docs/renderer.md); after specialization their SPIR-V must have none.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "kernel_inputs.h"
#include "pipeline_cache.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/spirv_compiler.h"
#include "variant_resolution.h"

namespace shimmer::render {
namespace {

constexpr std::uint32_t kOpControlBarrier = 224;

// OpControlBarrier instructions in a module (words after the 5-word header:
// word count in the high half, opcode in the low half).
int Barriers(const shading::Spirv& spirv) {
  int n = 0;
  for (std::size_t i = 5; i < spirv.size();) {
    const std::uint32_t words = spirv[i] >> 16;
    if ((spirv[i] & 0xffffu) == kOpControlBarrier) ++n;
    if (words == 0) break;
    i += words;
  }
  return n;
}

// The barriers of the kernel `settings` would run, specialized as the
// pipeline cache specializes it.
int SpecializedBarriers(const RenderSettings& settings) {
  auto variant = ResolveVariant(settings);
  EXPECT_TRUE(variant) << variant.error();
  if (!variant) return -1;
  auto module = KernelSpirv("render.comp", nullptr, false, false, nullptr);
  EXPECT_TRUE(module) << module.error();
  if (!module) return -1;
  const auto constants = KernelSpecialization(*variant, settings);
  auto specialized = shading::SpecializeCompute((*module)->spirv, constants);
  EXPECT_TRUE(specialized) << specialized.error();
  return specialized ? Barriers(*specialized) : -1;
}

RenderSettings Sphere() {
  RenderSettings s;
  s.scene = scene::LoadScene("sphere").value();
  s.material = s.scene.material;
  s.width = s.height = 16;
  s.frames = 1;
  return s;
}

TEST(KernelInputs, OnlyAnAdaptiveReferenceHoldsTheTileBarrier) {
  RenderSettings fixed = Sphere();
  fixed.reference_spp = 8;
  RenderSettings adaptive = Sphere();
  adaptive.reference_spp = 4;
  adaptive.reference_tolerance = 0.05;
  RenderSettings supersample = Sphere();
  supersample.variant = "supersample-2";
  RenderSettings filter = Sphere();
  filter.variant = "tk19";
  EXPECT_EQ(SpecializedBarriers(fixed), 0);
  EXPECT_EQ(SpecializedBarriers(supersample), 0);
  EXPECT_EQ(SpecializedBarriers(filter), 0);
  EXPECT_GE(SpecializedBarriers(adaptive), 2);  // the tile rule's two
}

}  // namespace
}  // namespace shimmer::render
