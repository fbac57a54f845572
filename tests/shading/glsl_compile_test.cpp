// Every GLSL file of the project compiles to SPIR-V (the shading core's files
// in their include context, the renderer's kernels as the renderer compiles
// them), and compile errors name the file and line.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "shimmer/shading/shading.h"
#include "shimmer/shading/user_variant.h"
#include "shimmer/shading/spirv_compiler.h"

namespace shimmer::shading {
namespace {

namespace fs = std::filesystem;

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

// The same for the spherical-Gaussian functions of sg.glsl, which no kernel calls yet.
const char* kSgKernel = R"(#version 460
#extension GL_GOOGLE_include_directive : require
#define real float
#include "core.glsl"
layout(local_size_x = 8) in;
layout(std430, binding = 0) buffer Out { vec4 values[]; };
void main() {
  uint i = gl_GlobalInvocationID.x;
  SG light;
  light.axis = normalize(vec3(0.1 * float(i), 0.2, 1.0));
  light.sharpness = 100.0;
  light.amplitude = vec3(1.0, 2.0, 3.0);
  vec3 n = vec3(0.0, 0.0, 1.0);
  vec3 v = normalize(vec3(0.5, 0.0, 0.01 * float(i)));
  vec3 f0 = vec3(0.04);
  SG ndf = distributionTermSG(n, 0.1);
  ASG warped = warpDistributionASG(ndf, v);
  vec3 a = specularTermSGWarp(light, n, 0.1, v, f0) + specularTermASGWarp(light, n, 0.1, v, f0) +
           sgInnerProduct(warpDistributionSG(ndf, v), light) + convolveASG_SG(warped, light) +
           sgIntegral(light) + sgEvaluate(light, v) + asgEvaluate(warped, v);
  values[i] = vec4(a, 1.0);
}
)";

// The project's GLSL as it is on disk: every *.glsl under shading/glsl and
// every *.comp under renderer/shaders, so that a new file is covered without
// touching this test.
std::vector<GlslFile> FilesOnDisk(const fs::path& root, const char* extension) {
  std::vector<GlslFile> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (!e.is_regular_file() || e.path().extension() != extension) continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    files.push_back({e.path().lexically_relative(root).generic_string(), text.str()});
  }
  std::sort(files.begin(), files.end(), [](const GlslFile& a, const GlslFile& b) { return a.name < b.name; });
  return files;
}

std::vector<GlslFile> FilesOnDisk(const char* folder, const char* extension) {
  return FilesOnDisk(fs::path(SHIMMER_SOURCE_DIR) / folder, extension);
}

// The shading core's GLSL: shading/glsl and the GLSL generated from
// shading/variant_table.json.
std::vector<GlslFile> ShadingFiles() {
  std::vector<GlslFile> files = FilesOnDisk("shading/glsl", ".glsl");
  for (GlslFile& f : FilesOnDisk(fs::path(SHIMMER_GENERATED_DIR), ".glsl")) files.push_back(std::move(f));
  std::sort(files.begin(), files.end(), [](const GlslFile& a, const GlslFile& b) { return a.name < b.name; });
  return files;
}

// The files core.glsl includes, in its order (each one's dependencies first).
std::vector<std::string> CoreOrder(const std::vector<GlslFile>& shading) {
  std::vector<std::string> order;
  for (const GlslFile& f : shading) {
    if (f.name != "core.glsl") continue;
    std::istringstream lines(f.text);
    std::string line;
    while (std::getline(lines, line)) {
      const auto open = line.find("#include \"");
      if (open == std::string::npos) continue;
      const auto start = open + 10, close = line.find('"', start);
      order.push_back(line.substr(start, close - start));
    }
  }
  return order;
}

const char* kPrefix = "#version 460\n#extension GL_GOOGLE_include_directive : require\n#define real float\n";

TEST(GlslCompile, ShadingSourcesOnDiskAreTheEmbeddedOnes) {
  const std::vector<GlslFile> disk = ShadingFiles();
  ASSERT_GE(disk.size(), 8u);
  for (const GlslFile& f : disk) {
    bool embedded = false;
    for (const auto& [name, text] : GlslSources())
      if (name == f.name) {
        embedded = true;
        EXPECT_EQ(text, f.text) << f.name << " differs from its embedded copy (stale build?)";
      }
    EXPECT_TRUE(embedded) << f.name << " is not embedded: add it to SHADING_GLSL in shading/CMakeLists.txt";
  }
  EXPECT_EQ(GlslSources().size(), disk.size());
}

TEST(GlslCompile, EveryShadingFileCompilesToSpirvInItsContext) {
  // Each file is an include-only fragment: compiled after the files core.glsl
  // includes before it, so that an error points at that file. A file core.glsl
  // does not include is compiled after the whole core.
  const std::vector<GlslFile> disk = ShadingFiles();
  const std::vector<std::string> order = CoreOrder(disk);
  ASSERT_GE(order.size(), 7u);
  int compiled = 0;
  for (const GlslFile& f : disk) {
    std::string body = kPrefix;
    if (std::find(order.begin(), order.end(), f.name) == order.end()) {
      body += "#include \"core.glsl\"\n";
      if (f.name != "core.glsl") body += "#include \"" + f.name + "\"\n";
    } else {
      for (const std::string& dep : order) {
        body += "#include \"" + dep + "\"\n";
        if (dep == f.name) break;
      }
    }
    body += "layout(local_size_x = 1) in;\nvoid main() {}\n";
    auto r = CompileCompute({"check_" + f.name + ".comp", body}, disk);
    EXPECT_TRUE(r.ok()) << f.name << ":\n" << r.error();
    ++compiled;
  }
  EXPECT_EQ(compiled, int(disk.size()));
}

// Every kernel compiles as the renderer compiles it: as it is, and, where it
// takes a user variant file (--variant-file), with SHIMMER_USER_VARIANT defined
// after #version, a user_params.glsl and a user_variant.glsl, as pipeline_cache.cpp's KernelFiles does.
TEST(GlslCompile, EveryKernelCompilesToSpirv) {
  std::vector<GlslFile> extra = ShadingFiles();
  for (GlslFile& f : FilesOnDisk("renderer/shaders", ".glsl")) extra.push_back(std::move(f));  // channels.glsl
  extra.push_back({"user_params.glsl", UserParamsGlsl(*ParseUserVariant("", "user.glsl"))});
  extra.push_back({"user_variant.glsl",
                   "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {\n"
                   "  return evalVariant(VARIANT_TK19, ndf, alpha * real(2), f, variantParams(p));\n}\n"});
  const std::vector<GlslFile> kernels = FilesOnDisk("renderer/shaders", ".comp");
  ASSERT_GE(kernels.size(), 1u);
  for (const GlslFile& k : kernels) {
    auto r = CompileCompute(k, extra);
    EXPECT_TRUE(r.ok()) << k.name << ":\n" << r.error();
    EXPECT_GT(r->size(), 100u) << k.name;
    if (k.text.find("SHIMMER_USER_VARIANT") == std::string::npos) continue;
    GlslFile user = k;
    user.text.insert(user.text.find('\n') + 1, "#define SHIMMER_USER_VARIANT\n#line 2\n");
    auto u = CompileCompute(user, extra);
    EXPECT_TRUE(u.ok()) << k.name << " with a user variant:\n" << u.error();
  }
}

TEST(GlslCompile, KernelCallingEveryVariantCompiles) {
  auto r = CompileCompute({"every_variant.comp", kEveryVariantKernel});
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_GT(r->size(), 100u);
  EXPECT_EQ((*r)[0], 0x07230203u);  // SPIR-V magic
}

TEST(GlslCompile, KernelCallingTheSgFunctionsCompiles) {
  auto r = CompileCompute({"sg.comp", kSgKernel});
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_GT(r->size(), 100u);
  EXPECT_EQ((*r)[0], 0x07230203u);
}

TEST(GlslCompile, ErrorNamesFileAndLine) {
  GlslFile user{"my_variant.glsl", "real myVariant(real x) {\n  return x +;\n}\n"};
  std::string main =
      "#version 460\n#extension GL_GOOGLE_include_directive : require\n#define real float\n"
      "#include \"my_variant.glsl\"\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
  auto r = CompileCompute({"kernel.comp", main}, std::span<const GlslFile>(&user, 1));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("my_variant.glsl:2"), std::string::npos) << r.error();
}

TEST(GlslCompile, MissingIncludeIsAnError) {
  std::string main =
      "#version 460\n#extension GL_GOOGLE_include_directive : require\n"
      "#include \"nowhere.glsl\"\nlayout(local_size_x = 1) in;\nvoid main() {}\n";
  auto r = CompileCompute({"kernel.comp", main});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("nowhere.glsl"), std::string::npos) << r.error();
}

}  // namespace
}  // namespace shimmer::shading
