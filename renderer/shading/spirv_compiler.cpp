#include "spirv_compiler.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>

#include <mutex>

#include "shimmer/renderer/shading.h"

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

}  // namespace shimmer::shading
