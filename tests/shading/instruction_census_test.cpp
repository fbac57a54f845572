// CountInstructions on small kernels whose counts are known by hand: what a
// function call, a comment, dead code and each class of instruction add.
#include <gtest/gtest.h>

#include <string>

#include "shimmer/shading/spirv_compiler.h"

namespace shimmer::shading {
namespace {

InstructionCensus Count(const std::string& body) {
  const std::string text = R"(#version 450
layout(local_size_x = 8) in;
layout(std430, binding = 0) buffer Data { float v[]; } data;
)" + body;
  auto spirv = CompileCompute({"census.comp", text});
  EXPECT_TRUE(spirv) << (spirv ? "" : spirv.error());
  if (!spirv) return {};
  auto census = CountInstructions(*spirv);
  EXPECT_TRUE(census) << (census ? "" : census.error());
  return census ? *census : InstructionCensus{};
}

const char* kBase = R"(
float shade(float x) { return exp(x) + sqrt(x); }
void main() {
  uint i = gl_GlobalInvocationID.x;
  float x = data.v[i];
  data.v[i] = shade(x) * 2.0;
}
)";

TEST(InstructionCensus, CountsEachClassOfTheInlinedKernel) {
  const InstructionCensus c = Count(kBase);
  EXPECT_EQ(c.transcendental, 2);  // exp, sqrt (in a function: inlined and counted)
  EXPECT_EQ(c.memory, 3);          // the load of the invocation id, of v[i], the store of v[i]
  EXPECT_EQ(c.alu, 2);             // the add and the multiply
}

TEST(InstructionCensus, ACommentOrDeadCodeAddsNothing) {
  const InstructionCensus base = Count(kBase);
  const InstructionCensus commented = Count(std::string("// a comment\n") + kBase +
                                            "float unused(float y) { return pow(y, 3.0) / y; }\n");
  EXPECT_EQ(commented.Total(), base.Total());
  EXPECT_EQ(commented.transcendental, base.transcendental);
}

TEST(InstructionCensus, EachAddedOperationLandsInItsClass) {
  const InstructionCensus base = Count(kBase);
  const InstructionCensus more = Count(R"(
float shade(float x) { return exp(x) + sqrt(x) + log(x) / (x + 1.0); }
void main() {
  uint i = gl_GlobalInvocationID.x;
  float x = data.v[i];
  data.v[i] = shade(x) * 2.0;
  data.v[i + 1u] = min(x, 1.0);
}
)");
  EXPECT_EQ(more.transcendental, base.transcendental + 2);  // log, the division
  EXPECT_EQ(more.memory, base.memory + 1);                  // the second store
  // Two adds (the sum's third term and x + 1), the index add and min.
  EXPECT_EQ(more.alu, base.alu + 4);
}

// The one canonicalization behind a kernel's cached hash and census gives
// exactly what the two separate calls give.
TEST(InstructionCensus, OneSummaryGivesTheHashAndTheCensus) {
  const std::string text = std::string(R"(#version 450
layout(local_size_x = 8) in;
layout(std430, binding = 0) buffer Data { float v[]; } data;
)") + kBase;
  auto spirv = CompileCompute({"census.comp", text});
  ASSERT_TRUE(spirv) << spirv.error();
  auto summary = SummarizeKernel(*spirv);
  ASSERT_TRUE(summary) << summary.error();
  auto hash = CanonicalSpirvHash(*spirv);
  auto census = CountInstructions(*spirv);
  ASSERT_TRUE(hash && census);
  EXPECT_EQ(summary->hash, *hash);
  EXPECT_EQ(summary->hash.size(), 16u);
  EXPECT_EQ(summary->census.alu, census->alu);
  EXPECT_EQ(summary->census.transcendental, census->transcendental);
  EXPECT_EQ(summary->census.memory, census->memory);
  EXPECT_EQ(summary->census.control, census->control);
  EXPECT_EQ(summary->census.transcendental, 2);  // exp, sqrt: the census of kBase
}

}  // namespace
}  // namespace shimmer::shading
