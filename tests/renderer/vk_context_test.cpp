// The small Vulkan API of renderer/vk on its own: that the validation
// messenger really reports (so that a clean render under validation means
// something), and that an injected device loss fails the dispatch it hits and
// every later one.
#include <gtest/gtest.h>

#include <cstring>

#include "shimmer/shading/spirv_compiler.h"
#include "vk.h"

namespace shimmer::vk {
namespace {

constexpr const char* kWriteOne = R"(#version 450
layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer Out { uint value[]; };
void main() { value[0] = 1u; }
)";

std::vector<std::uint32_t> WriteOneSpirv() {
  auto spirv = shading::CompileCompute({"write_one.comp", kWriteOne});
  EXPECT_TRUE(spirv.ok()) << spirv.error();
  return spirv.ok() ? *spirv : shading::Spirv{};
}

TEST(GpuVkContext, ValidationLayerReportsABindingOfTheWrongKind) {
  ContextOptions options;
  options.validation = true;
  auto ctx = Context::Create(options);
  ASSERT_TRUE(ctx) << ctx.error();
  if (!ctx.value()->validation_active()) GTEST_SKIP() << "VK_LAYER_KHRONOS_validation is not installed";
  const std::vector<std::uint32_t> spirv = WriteOneSpirv();

  // The shader declares a storage buffer; the layout says uniform.
  const BufferKind wrong[] = {BufferKind::kUniform};
  auto bad = ctx.value()->CreatePipeline(spirv, {}, wrong, 0);
  std::vector<std::string> messages = ctx.value()->TakeValidationMessages();
  ASSERT_FALSE(messages.empty());
  EXPECT_EQ(messages.front().rfind("error: ", 0), 0u) << messages.front();
  EXPECT_NE(messages.front().find("descriptor"), std::string::npos) << messages.front();

  const BufferKind right[] = {BufferKind::kStorage};
  auto good = ctx.value()->CreatePipeline(spirv, {}, right, 0);
  ASSERT_TRUE(good) << good.error();
  auto out = ctx.value()->CreateBuffer(16);
  ASSERT_TRUE(out) << out.error();
  Buffer* buffers[] = {out->get()};
  auto r = ctx.value()->Dispatch(*good.value(), buffers, {}, 1, 1);
  EXPECT_TRUE(r.ok()) << r.error();
  std::uint32_t value = 0;
  std::memcpy(&value, out.value()->data(), sizeof value);
  EXPECT_EQ(value, 1u);
  EXPECT_TRUE(ctx.value()->TakeValidationMessages().empty());
}

TEST(GpuVkContext, InjectedDeviceLossFailsThatDispatchAndEveryLaterOne) {
  ContextOptions options;
  options.lose_device_after_dispatches = 1;
  auto ctx = Context::Create(options);
  ASSERT_TRUE(ctx) << ctx.error();
  const BufferKind kinds[] = {BufferKind::kStorage};
  auto pipeline = ctx.value()->CreatePipeline(WriteOneSpirv(), {}, kinds, 0);
  ASSERT_TRUE(pipeline) << pipeline.error();
  auto out = ctx.value()->CreateBuffer(16);
  ASSERT_TRUE(out) << out.error();
  Buffer* buffers[] = {out->get()};
  EXPECT_TRUE(ctx.value()->Dispatch(*pipeline.value(), buffers, {}, 1, 1).ok());
  auto lost = ctx.value()->Dispatch(*pipeline.value(), buffers, {}, 1, 1);
  EXPECT_EQ(lost.error(), "the GPU dispatch failed: device lost");
  EXPECT_EQ(lost.code(), ErrorCode::kDeviceLost);
  EXPECT_EQ(ctx.value()->Dispatch(*pipeline.value(), buffers, {}, 1, 1).error(), "device lost");
}

}  // namespace
}  // namespace shimmer::vk
