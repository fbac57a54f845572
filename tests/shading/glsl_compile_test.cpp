// Every GLSL source of the shading core compiles to SPIR-V, and compile errors
// name the file and line.
#include <gtest/gtest.h>

#include "shimmer/renderer/shading.h"
#include "spirv_compiler.h"

namespace shimmer::shading {
namespace {

// A compute shader that calls every entry point of the core so that nothing
// is dead-code-eliminated before validation.
const char* kEveryVariantKernel = R"(#version 460
#extension GL_GOOGLE_include_directive : require
#define real float
#include "core.glsl"
layout(local_size_x = 8) in;
layout(std430, binding = 0) buffer Out { vec4 values[]; };
void main() {
  uint i = gl_GlobalInvocationID.x;
  ShadingFootprint f;
  f.hpp = vec2(0.01 * float(i), 0.02);
  f.dhpp_dx = vec2(0.03, 0.0);
  f.dhpp_dy = vec2(0.0, 0.04);
  f.n = vec3(0.0, 0.0, 1.0);
  f.dn_dx = vec3(0.03, 0.0, 0.0);
  f.dn_dy = vec3(0.0, 0.04, 0.0);
  f.dng_dx = f.dn_dx;
  f.dng_dy = f.dn_dy;
  VariantParams p;
  p.fp_max = 1.0; p.fp_min_cap = 0.1; p.sigma2 = 0.25; p.kappa = 0.18;
  FilteredNdf r = evalVariant(int(i) % VARIANT_COUNT, int(i / 16u) % 2, vec2(0.05, 0.1), f, p);
  values[i] = vec4(r.slope_density, r.density, r.alpha_eff);
}
)";

TEST(GlslCompile, EveryCoreFileCompilesToSpirv) {
  // Each file on its own (after its dependencies), so an error points at it.
  std::string prefix = "#version 460\n#extension GL_GOOGLE_include_directive : require\n#define real float\n";
  int compiled = 0;
  for (const auto& [name, text] : GlslSources()) {
    if (name == "core.glsl") continue;
    std::string body = prefix;
    for (const auto& [dep, unused] : GlslSources()) {
      if (dep == "core.glsl") continue;
      body += "#include \"" + std::string(dep) + "\"\n";
      if (dep == name) break;
    }
    body += "layout(local_size_x = 1) in;\nvoid main() {}\n";
    auto r = CompileCompute({"check_" + std::string(name) + ".comp", body});
    EXPECT_TRUE(r.ok()) << name << ":\n" << r.error();
    ++compiled;
  }
  EXPECT_GE(compiled, 4);
}

TEST(GlslCompile, KernelCallingEveryVariantCompiles) {
  auto r = CompileCompute({"every_variant.comp", kEveryVariantKernel});
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_GT(r->size(), 100u);
  EXPECT_EQ((*r)[0], 0x07230203u);  // SPIR-V magic
}

TEST(GlslCompile, ErrorNamesFileAndLine) {
  GlslFile user{"my_variant.glsl", "real myVariant(real x) {\n  return x +;\n}\n"};
  std::string main = "#version 460\n#extension GL_GOOGLE_include_directive : require\n#define real float\n"
                     "#include \"my_variant.glsl\"\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
  auto r = CompileCompute({"kernel.comp", main}, std::span<const GlslFile>(&user, 1));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("my_variant.glsl:2"), std::string::npos) << r.error();
}

TEST(GlslCompile, MissingIncludeIsAnError) {
  std::string main = "#version 460\n#extension GL_GOOGLE_include_directive : require\n"
                     "#include \"nowhere.glsl\"\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
  auto r = CompileCompute({"kernel.comp", main});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("nowhere.glsl"), std::string::npos) << r.error();
}

}  // namespace
}  // namespace shimmer::shading
