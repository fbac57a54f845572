// GLSL -> SPIR-V in process (libglslang), for the renderer's kernels, user
// variant files and the shading-core compile test. No Vulkan here.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "shimmer/core/result.h"

namespace shimmer::shading {

struct GlslFile {
  std::string name;  // what `#include "name"` and error messages use
  std::string text;
};

using Spirv = std::vector<std::uint32_t>;

// Compiles a compute shader for Vulkan 1.2 (SPIR-V 1.5). `#include "x"`
// resolves against `extra` first, then the shading core (GlslSources()). The
// error is glslang's log, whose lines start with "ERROR: <file>:<line>:".
Result<Spirv> CompileCompute(const GlslFile& main, std::span<const GlslFile> extra = {});

}  // namespace shimmer::shading
