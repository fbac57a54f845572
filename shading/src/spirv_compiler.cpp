#include "shimmer/shading/spirv_compiler.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>

#include <spirv-tools/libspirv.h>
#include <spirv-tools/optimizer.hpp>

#include <mutex>
#include <unordered_map>

#include "shimmer/core/content_hash.h"

#include "shimmer/shading/shading.h"

namespace shimmer::shading {

namespace {

class SourceIncluder : public glslang::TShader::Includer {
 public:
  explicit SourceIncluder(std::span<const GlslFile> extra) : extra_(extra) {}

  IncludeResult* includeLocal(const char* name, const char*, size_t) override { return Find(name); }
  IncludeResult* includeSystem(const char* name, const char*, size_t) override { return Find(name); }
  void releaseInclude(IncludeResult* result) override { delete result; }

 private:
  IncludeResult* Find(std::string_view name) {
    for (const GlslFile& f : extra_)
      if (f.name == name) return new IncludeResult(f.name, f.text.data(), f.text.size(), nullptr);
    for (const auto& [file, text] : GlslSources())
      if (file == name) return new IncludeResult(std::string(file), text.data(), text.size(), nullptr);
    return nullptr;  // glslang reports "could not process include directive" with the name
  }

  std::span<const GlslFile> extra_;
};

void InitializeOnce() {
  static std::once_flag once;
  std::call_once(once, [] { glslang::InitializeProcess(); });
}

}  // namespace

Result<Spirv> CompileCompute(const GlslFile& main, std::span<const GlslFile> extra) {
  InitializeOnce();
  glslang::TShader shader(EShLangCompute);
  const char* text = main.text.c_str();
  const int length = static_cast<int>(main.text.size());
  const char* name = main.name.c_str();
  shader.setStringsWithLengthsAndNames(&text, &length, &name, 1);
  shader.setEnvInput(glslang::EShSourceGlsl, EShLangCompute, glslang::EShClientVulkan, 100);
  shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_2);
  shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_5);
  const auto messages = static_cast<EShMessages>(EShMsgSpvRules | EShMsgVulkanRules);
  SourceIncluder includer(extra);
  if (!shader.parse(GetDefaultResources(), 460, false, messages, includer)) {
    return Result<Spirv>::Failure(std::string(shader.getInfoLog()) + shader.getInfoDebugLog());
  }
  glslang::TProgram program;
  program.addShader(&shader);
  if (!program.link(messages)) {
    return Result<Spirv>::Failure(std::string(program.getInfoLog()) + program.getInfoDebugLog());
  }
  glslang::SpvOptions options;
  options.disableOptimizer = false;
  Spirv words;
  glslang::GlslangToSpv(*program.getIntermediate(EShLangCompute), words, &options);
  if (words.empty())
    return Result<Spirv>::Failure(main.name + ": SPIR-V generation produced no code", ErrorCode::kInternal);
  return words;
}

std::string CompileKey(const GlslFile& main, std::span<const GlslFile> extra) {
  const glslang::Version v = glslang::GetVersion();
  std::string all = "glslang " + std::to_string(v.major) + "." + std::to_string(v.minor) + "." +
                    std::to_string(v.patch) + v.flavor + '\0';
  auto add = [&](std::string_view name, std::string_view text) {
    all.append(name);
    all += '\0';
    all.append(text);
    all += '\0';
  };
  add(main.name, main.text);
  for (const GlslFile& f : extra) add(f.name, f.text);
  for (const auto& [name, text] : GlslSources()) add(name, text);
  return Fnv1a64Hex(all);
}

std::string SpecializerVersion() { return spvSoftwareVersionDetailsString(); }

Result<Spirv> SpecializeCompute(const Spirv& module, std::span<const std::int32_t> constants) {
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> values;
  for (std::size_t i = 0; i < constants.size(); ++i)
    values[static_cast<std::uint32_t>(i)] = {static_cast<std::uint32_t>(constants[i])};
  spvtools::Optimizer optimizer(SPV_ENV_VULKAN_1_2);
  std::string messages;
  optimizer.SetMessageConsumer([&](spv_message_level_t level, const char*, const spv_position_t&, const char* text) {
    if (level <= SPV_MSG_ERROR) messages += std::string(text) + "; ";
  });
  optimizer.RegisterPass(spvtools::CreateSetSpecConstantDefaultValuePass(values))
      .RegisterPass(spvtools::CreateFreezeSpecConstantValuePass())
      .RegisterPass(spvtools::CreateFoldSpecConstantOpAndCompositePass())
      .RegisterPass(spvtools::CreateDeadBranchElimPass())
      .RegisterPass(spvtools::CreateBlockMergePass())
      .RegisterPass(spvtools::CreateEliminateDeadFunctionsPass())
      .RegisterPass(spvtools::CreateAggressiveDCEPass());
  // glslang's output is valid SPIR-V; validating it again would cost as much
  // as the passes.
  spvtools::OptimizerOptions options;
  options.set_run_validator(false);
  Spirv out;
  if (!optimizer.Run(module.data(), module.size(), &out, options))
    return Result<Spirv>::Failure("specializing the kernel failed: " + messages, ErrorCode::kInternal);
  return out;
}

}  // namespace shimmer::shading
