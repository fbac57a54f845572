// GLSL -> SPIR-V in process (libglslang), for the renderer's kernels, user
// variant files and the shading-core compile test. No Vulkan here.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/shading/shading.h"

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

// A hash of everything CompileCompute(main, extra) reads: the texts, the
// shading core it may include and the compiler's version. Equal keys, equal
// SPIR-V: the name of a compiled module in a cache.
std::string CompileKey(const GlslFile& main, std::span<const GlslFile> extra = {});

// `module` with its int specialization constants 0..k-1 set to `constants`
// and frozen, and the code they make unreachable removed (SPIRV-Tools:
// freeze, fold, dead-branch and dead-function elimination, ADCE). The kernel
// holds every variant, scene kind and NDF; a driver that compiles it whole
// (lavapipe: SPIR-V -> NIR of every function before specializing) spends 4x
// longer than on the one variant left here. Changes no arithmetic that
// remains.
Result<Spirv> SpecializeCompute(const Spirv& module, std::span<const std::int32_t> constants);
// The optimizer's version, for cache keys of specialized modules.
std::string SpecializerVersion();

// A hash of what `module` computes, not of how its source was written
// (spirv_canonical.cpp). A copy of the module has every function inlined into
// the entry point and the frozen constants propagated (so a variant's code
// leaves the kernels of the other variants), its debug and non-semantic
// instructions stripped; then every id is hashed by its content (a type or
// constant by its definition, a local value by its place), from the entry
// point down. A comment, a renamed local, dead code, an edit of another
// variant or another order of the shared declarations (glslang declares a
// constant where it first meets it) leave it as it was; an edit of code the
// kernel runs moves it. The optimizer keeps the arithmetic, so equal hashes
// mean equal computations. Job ids are built on it (shimmer/experiments/job.h).
Result<std::string> CanonicalSpirvHash(const Spirv& module);
// The static instruction counts (InstructionCensus, shading.h) of the canonical form of `module` (the code this
// kernel runs, every function inlined), by the unit they need: a
// device-independent cost beside timings on one device. A vector operation
// counts once; loops count once. `memory` is loads and stores of buffers,
// images and push constants (not of locals), image and atomic operations;
// `transcendental` is exp, log, pow, sqrt, rsqrt, trigonometry, length,
// normalize, distance and division; `control` is branches and barriers;
// `alu` is the rest of the arithmetic, comparisons, conversions and selects.
Result<InstructionCensus> CountInstructions(const Spirv& module);
// Both from one canonicalization, which is nearly all of either's cost
// (about 0.7 s for a filter kernel).
struct KernelSummary {
  std::string hash;  // CanonicalSpirvHash
  InstructionCensus census;  // CountInstructions
};
Result<KernelSummary> SummarizeKernel(const Spirv& module);
// Names the canonical form (its passes and the optimizer's version), for
// cache keys of canonical hashes.
std::string CanonicalHashVersion();

}  // namespace shimmer::shading
