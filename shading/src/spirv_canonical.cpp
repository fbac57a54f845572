// CanonicalSpirvHash: a structural hash of a SPIR-V module from its entry
// point. Ids are replaced by hashes of what defines them, so the numbering
// and the order of the module's declarations drop out.
#include <glslang/SPIRV/GLSL.std.450.h>
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
#include "shimmer/shading/spirv_compiler.h"

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


// The module every function inlined into the entry point, the frozen
// constants propagated and the debug info stripped, as parsed instructions.
Result<std::vector<Instruction>> CanonicalInstructions(const Spirv& module) {
  using R = Result<std::vector<Instruction>>;
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
  // Scalar replacement splits the structs that inlining leaves as function
  // locals (a struct argument, a struct a helper returns) into one variable
  // per field, which the store eliminations then turn into SSA values, and
  // simplification folds the composite constructs and extracts left around
  // them: so moving code into a helper that takes or returns a struct keeps
  // the kernel's hash, as it keeps its arithmetic.
  optimizer.RegisterPass(spvtools::CreateMergeReturnPass())
      .RegisterPass(spvtools::CreateInlineExhaustivePass())
      .RegisterPass(spvtools::CreateEliminateDeadFunctionsPass())
      .RegisterPass(spvtools::CreatePrivateToLocalPass())
      .RegisterPass(spvtools::CreateScalarReplacementPass(0))
      .RegisterPass(spvtools::CreateLocalSingleStoreElimPass())
      .RegisterPass(spvtools::CreateLocalMultiStoreElimPass())
      .RegisterPass(spvtools::CreateCCPPass())
      .RegisterPass(spvtools::CreateSimplificationPass())
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
  return instructions;
}

// Which unit an extended GLSL.std.450 instruction needs: the ones a GPU runs
// on its special-function unit (exp, log, sqrt, rsqrt, trigonometry), and
// the vector helpers built on them (length, normalize, distance: a sqrt or
// rsqrt each), are transcendental; min, max, clamp, mix, fma, floor, abs and
// the like are plain ALU.
bool Transcendental(std::uint32_t glsl) {
  switch (glsl) {
    case GLSLstd450Sin: case GLSLstd450Cos: case GLSLstd450Tan: case GLSLstd450Asin: case GLSLstd450Acos:
    case GLSLstd450Atan: case GLSLstd450Atan2: case GLSLstd450Sinh: case GLSLstd450Cosh: case GLSLstd450Tanh:
    case GLSLstd450Asinh: case GLSLstd450Acosh: case GLSLstd450Atanh: case GLSLstd450Pow: case GLSLstd450Exp:
    case GLSLstd450Log: case GLSLstd450Exp2: case GLSLstd450Log2: case GLSLstd450Sqrt:
    case GLSLstd450InverseSqrt: case GLSLstd450Length: case GLSLstd450Distance: case GLSLstd450Normalize:
    case GLSLstd450Refract:
      return true;
    default: return false;
  }
}

bool MemoryStorage(std::uint32_t storage_class) {
  switch (storage_class) {
    case spv::StorageClassFunction:
    case spv::StorageClassPrivate: return false;  // registers once the optimizer is through
    default: return true;
  }
}

}  // namespace

// Bump when the passes or the structural hash change.
std::string CanonicalHashVersion() { return "structural-2 " + SpecializerVersion(); }

namespace {

std::string HexOf(std::uint64_t h) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return std::string(hex);
}

InstructionCensus CensusOf(const std::vector<Instruction>& instructions) {
  InstructionCensus census;
  std::uint32_t glsl_set = 0;
  std::unordered_map<std::uint32_t, std::uint32_t> storage;  // pointer id -> storage class
  bool in_function = false;
  for (const Instruction& x : instructions) {
    const auto& w = x.words;
    switch (x.opcode) {
      case spv::OpExtInstImport: glsl_set = x.result; continue;
      case spv::OpVariable: storage[x.result] = w[3]; continue;
      case spv::OpAccessChain:
      case spv::OpInBoundsAccessChain:
      case spv::OpPtrAccessChain:
        if (auto it = storage.find(w[3]); it != storage.end()) storage[x.result] = it->second;
        continue;
      case spv::OpFunction: in_function = true; continue;
      case spv::OpFunctionEnd: in_function = false; continue;
      default: break;
    }
    if (!in_function) continue;
    switch (x.opcode) {
      case spv::OpLabel: case spv::OpPhi: case spv::OpLoopMerge: case spv::OpSelectionMerge:
      case spv::OpFunctionParameter: case spv::OpUndef: case spv::OpNop:
        break;  // no work of their own
      case spv::OpCompositeConstruct: case spv::OpCompositeExtract: case spv::OpCompositeInsert:
      case spv::OpVectorShuffle: case spv::OpCopyObject:
        break;  // register moves a compiler folds away
      case spv::OpBranch: case spv::OpBranchConditional: case spv::OpSwitch: case spv::OpReturn:
      case spv::OpReturnValue: case spv::OpKill: case spv::OpUnreachable: case spv::OpControlBarrier:
      case spv::OpMemoryBarrier: case spv::OpFunctionCall:
        ++census.control;
        break;
      case spv::OpLoad: {
        auto it = storage.find(w[3]);
        if (it == storage.end() || MemoryStorage(it->second)) ++census.memory;
        break;
      }
      case spv::OpStore: {
        auto it = storage.find(w[1]);
        if (it == storage.end() || MemoryStorage(it->second)) ++census.memory;
        break;
      }
      case spv::OpFDiv: case spv::OpFRem: case spv::OpFMod:
        ++census.transcendental;  // a reciprocal on the special-function unit
        break;
      case spv::OpExtInst:
        if (w[3] == glsl_set && Transcendental(w[4])) ++census.transcendental;
        else ++census.alu;
        break;
      default:
        if ((x.opcode >= spv::OpImageSampleImplicitLod && x.opcode <= spv::OpImageWrite) ||
            (x.opcode >= spv::OpAtomicLoad && x.opcode <= spv::OpAtomicXor) ||
            (x.opcode >= spv::OpImageSparseSampleImplicitLod && x.opcode <= spv::OpImageSparseRead) ||
            x.opcode == spv::OpCopyMemory)
          ++census.memory;
        else
          ++census.alu;  // arithmetic, comparisons, conversions, selects, bit and group operations
    }
  }
  return census;
}

}  // namespace

Result<std::string> CanonicalSpirvHash(const Spirv& module) {
  auto instructions = CanonicalInstructions(module);
  if (!instructions) return instructions.failure();
  return HexOf(StructuralHash(std::move(*instructions)).Module());
}

Result<InstructionCensus> CountInstructions(const Spirv& module) {
  auto instructions = CanonicalInstructions(module);
  if (!instructions) return instructions.failure();
  return CensusOf(*instructions);
}

Result<KernelSummary> SummarizeKernel(const Spirv& module) {
  auto instructions = CanonicalInstructions(module);
  if (!instructions) return instructions.failure();
  KernelSummary summary;
  summary.census = CensusOf(*instructions);
  summary.hash = HexOf(StructuralHash(std::move(*instructions)).Module());
  return summary;
}

}  // namespace shimmer::shading
