// CanonicalSpirvHash: a structural hash of a SPIR-V module from its entry
// point. Ids are replaced by hashes of what defines them, so the numbering
// and the order of the module's declarations drop out.
#include <glslang/SPIRV/spirv.hpp>
#include <spirv-tools/libspirv.h>
#include <spirv-tools/optimizer.hpp>

#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "shimmer/core/content_hash.h"
#include "spirv_compiler.h"

namespace shimmer::shading {

namespace {

struct Instruction {
  std::uint32_t opcode = 0, result = 0;
  std::vector<std::uint32_t> words;  // the result id word zeroed
  std::vector<bool> is_id;           // per word: an id operand (the result id excluded)
};

spv_result_t Collect(void* user, const spv_parsed_instruction_t* p) {
  auto* out = static_cast<std::vector<Instruction>*>(user);
  Instruction in;
  in.opcode = p->opcode;
  in.result = p->result_id;
  in.words.assign(p->words, p->words + p->num_words);
  in.is_id.assign(p->num_words, false);
  for (std::uint16_t k = 0; k < p->num_operands; ++k) {
    const spv_parsed_operand_t& o = p->operands[k];
    if (o.type == SPV_OPERAND_TYPE_RESULT_ID) {
      in.words[o.offset] = 0;
      continue;
    }
    const bool id = o.type == SPV_OPERAND_TYPE_ID || o.type == SPV_OPERAND_TYPE_TYPE_ID ||
                    o.type == SPV_OPERAND_TYPE_MEMORY_SEMANTICS_ID || o.type == SPV_OPERAND_TYPE_SCOPE_ID;
    if (id)
      for (std::uint16_t w = 0; w < o.num_words; ++w) in.is_id[o.offset + w] = true;
  }
  out->push_back(std::move(in));
  return SPV_SUCCESS;
}

std::uint64_t Fnv(const std::vector<std::uint64_t>& values) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (std::uint64_t v : values)
    for (int b = 0; b < 8; ++b) {
      h ^= (v >> (8 * b)) & 0xff;
      h *= 0x100000001b3ull;
    }
  return h;
}

class StructuralHash {
 public:
  explicit StructuralHash(std::vector<Instruction> instructions) : in_(std::move(instructions)) {
    std::size_t function_start = 0;
    bool in_function = false;
    for (std::size_t i = 0; i < in_.size(); ++i) {
      const Instruction& x = in_[i];
      switch (x.opcode) {
        case spv::OpFunction:
          in_function = true, function_start = i;
          break;
        case spv::OpFunctionEnd:
          in_function = false, functions_[in_[function_start].result] = {function_start, i + 1};
          break;
        case spv::OpDecorate:
        case spv::OpMemberDecorate:
        case spv::OpDecorateId:
        case spv::OpDecorateString:
        case spv::OpMemberDecorateString:
          decorations_[x.words[1]].push_back(i);
          break;
        default:
          if (!in_function && x.result) globals_[x.result] = i;
      }
    }
  }

  std::uint64_t Module() {
    std::vector<std::uint64_t> parts;
    for (std::size_t i = 0; i < in_.size(); ++i) {
      const std::uint32_t op = in_[i].opcode;
      if (op == spv::OpCapability || op == spv::OpExtension || op == spv::OpMemoryModel ||
          op == spv::OpEntryPoint || op == spv::OpExecutionMode || op == spv::OpExecutionModeId)
        parts.push_back(Content(in_[i], nullptr));
    }
    std::sort(parts.begin(), parts.end());  // their order means nothing
    return Fnv(parts);
  }

 private:
  // A decoration of `target` without the target itself.
  std::uint64_t Decorations(std::uint32_t target, std::map<std::uint32_t, std::uint32_t>* locals) {
    std::vector<std::uint64_t> parts;
    if (auto it = decorations_.find(target); it != decorations_.end())
      for (std::size_t i : it->second) {
        Instruction d = in_[i];
        d.words[1] = 0, d.is_id[1] = false;
        parts.push_back(Content(d, locals));
      }
    std::sort(parts.begin(), parts.end());
    return Fnv(parts);
  }

  // The instruction with every id operand replaced by the hash of its
  // definition (globals, functions) or its local number (`locals`).
  std::uint64_t Content(const Instruction& x, std::map<std::uint32_t, std::uint32_t>* locals) {
    std::vector<std::uint64_t> parts{x.opcode};
    for (std::size_t w = 1; w < x.words.size(); ++w) parts.push_back(x.is_id[w] ? Id(x.words[w], locals) : x.words[w]);
    return Fnv(parts);
  }

  std::uint64_t Id(std::uint32_t id, std::map<std::uint32_t, std::uint32_t>* locals) {
    if (functions_.count(id)) return Function(id);
    if (globals_.count(id)) return Global(id);
    if (!locals) return 0x9e3779b97f4a7c15ull;  // not defined in the module's scope
    auto [it, inserted] = locals->try_emplace(id, std::uint32_t(locals->size()));
    return 0x10000ull + it->second;
  }

  std::uint64_t Global(std::uint32_t id) {
    if (auto it = memo_.find(id); it != memo_.end()) return it->second;
    memo_[id] = 0x51ed27ull;  // a cycle (forward pointers) reads this
    const std::uint64_t h = Fnv({Content(in_[globals_.at(id)], nullptr), Decorations(id, nullptr)});
    return memo_[id] = h;
  }

  std::uint64_t Function(std::uint32_t id) {
    if (auto it = memo_.find(id); it != memo_.end()) return it->second;
    memo_[id] = 0xf0ca11ull;  // recursion (not in GLSL) reads this
    const auto [begin, end] = functions_.at(id);
    std::map<std::uint32_t, std::uint32_t> locals;
    std::vector<std::uint64_t> parts;
    for (std::size_t i = begin; i < end; ++i) {
      const Instruction& x = in_[i];
      if (x.result && i != begin) parts.push_back(Id(x.result, &locals));
      parts.push_back(Content(x, &locals));
      if (x.result && i != begin) parts.push_back(Decorations(x.result, &locals));
    }
    parts.push_back(Decorations(id, nullptr));
    return memo_[id] = Fnv(parts);
  }

  std::vector<Instruction> in_;
  std::unordered_map<std::uint32_t, std::pair<std::size_t, std::size_t>> functions_;
  std::unordered_map<std::uint32_t, std::size_t> globals_;
  std::unordered_map<std::uint32_t, std::vector<std::size_t>> decorations_;
  std::unordered_map<std::uint32_t, std::uint64_t> memo_;
};

}  // namespace

// Bump when the passes or the structural hash change.
std::string CanonicalHashVersion() { return "structural-1 " + SpecializerVersion(); }

Result<std::string> CanonicalSpirvHash(const Spirv& module) {
  using R = Result<std::string>;
  spvtools::Optimizer optimizer(SPV_ENV_VULKAN_1_2);
  std::string messages;
  optimizer.SetMessageConsumer([&](spv_message_level_t level, const char*, const spv_position_t&, const char* text) {
    if (level <= SPV_MSG_ERROR) messages += std::string(text) + "; ";
  });
  // The variant, the derivative source and the scene's kinds reach the
  // shading functions as arguments (the C++ oracle compiles the same code):
  // only inlining them into main and propagating the frozen constants shows
  // which code this kernel runs. Source lines (OpLine) sit inside function
  // bodies: they go too.
  optimizer.RegisterPass(spvtools::CreateMergeReturnPass())
      .RegisterPass(spvtools::CreateInlineExhaustivePass())
      .RegisterPass(spvtools::CreateEliminateDeadFunctionsPass())
      .RegisterPass(spvtools::CreateLocalSingleStoreElimPass())
      .RegisterPass(spvtools::CreateLocalMultiStoreElimPass())
      .RegisterPass(spvtools::CreateCCPPass())
      .RegisterPass(spvtools::CreateDeadBranchElimPass())
      .RegisterPass(spvtools::CreateAggressiveDCEPass())
      .RegisterPass(spvtools::CreateStripDebugInfoPass())
      .RegisterPass(spvtools::CreateStripNonSemanticInfoPass())
      .RegisterPass(spvtools::CreateEliminateDeadFunctionsPass());
  optimizer.RegisterPass(spvtools::CreateStripDebugInfoPass())
      .RegisterPass(spvtools::CreateStripNonSemanticInfoPass());
  spvtools::OptimizerOptions options;
  options.set_run_validator(false);
  Spirv stripped;
  if (!optimizer.Run(module.data(), module.size(), &stripped, options))
    return R::Failure("canonicalizing the kernel failed: " + messages, ErrorCode::kInternal);
  std::vector<Instruction> instructions;
  spv_context context = spvContextCreate(SPV_ENV_VULKAN_1_2);
  spv_diagnostic diagnostic = nullptr;
  const spv_result_t parsed = spvBinaryParse(context, &instructions, stripped.data(), stripped.size(), nullptr,
                                             Collect, &diagnostic);
  std::string why = diagnostic && diagnostic->error ? diagnostic->error : "not a SPIR-V module";
  spvDiagnosticDestroy(diagnostic);
  spvContextDestroy(context);
  if (parsed != SPV_SUCCESS) return R::Failure("canonicalizing the kernel failed: " + why, ErrorCode::kInternal);
  const std::uint64_t h = StructuralHash(std::move(instructions)).Module();
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return std::string(hex);
}

}  // namespace shimmer::shading
