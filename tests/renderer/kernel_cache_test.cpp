// The on-disk kernel cache: its file format refuses damaged and foreign files
// with one warning naming them, a folder is trimmed oldest first, the Vulkan
// pipeline cache refuses data of another device or driver before the driver
// sees it, and `shimmer render` end to end: a second render finds the
// kernel it compiled, a damaged cache is rebuilt and changes no pixel.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "cli_run.h"
#include "kernel_disk_cache.h"
#include "shimmer/shading/spirv_compiler.h"
#include "temp_dir.h"
#include "vk.h"

namespace shimmer::render {
namespace {

namespace fs = std::filesystem;
using shimmer::testing::TempDir;

std::string ReadAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void Overwrite(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << bytes;
}

// ReadCacheFile's result and what it printed on stderr.
struct Read {
  std::optional<std::string> payload;
  std::string warnings;
};
Read ReadCapturingWarnings(const fs::path& p, std::string_view kind) {
  ::testing::internal::CaptureStderr();
  Read r;
  r.payload = ReadCacheFile(p, kind);
  r.warnings = ::testing::internal::GetCapturedStderr();
  return r;
}

TEST(KernelCache, FileKeepsItsPayloadExactly) {
  TempDir dir;
  std::string payload("\x03\x02\x23\x07 binary\n\0 bytes", 19);
  WriteCacheFile(dir / "sub" / "a.spv", "spirv", payload);  // creates the folder
  Read r = ReadCapturingWarnings(dir / "sub" / "a.spv", "spirv");
  ASSERT_TRUE(r.payload);
  EXPECT_EQ(*r.payload, payload);
  EXPECT_EQ(r.warnings, "");
  // Written through a temporary name: nothing else is left in the folder.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "sub"), fs::directory_iterator()), 1);
}

TEST(KernelCache, AbsentFileIsNoHitAndNoWarning) {
  TempDir dir;
  Read r = ReadCapturingWarnings(dir / "missing.spv", "spirv");
  EXPECT_FALSE(r.payload);
  EXPECT_EQ(r.warnings, "");
}

TEST(KernelCache, DamagedOrForeignFilesAreIgnoredWithOneWarningNamingThem) {
  TempDir dir;
  const fs::path good = dir / "good.spv";
  WriteCacheFile(good, "spirv", std::string(64, 'x'));
  const std::string bytes = ReadAll(good);
  const std::size_t header = bytes.find('\n') + 1;
  struct Case {
    const char* name;
    std::string content;
    const char* reason;
  };
  std::string flipped = bytes;
  flipped[header + 10] = 'y';
  std::string future = bytes;
  future.replace(future.find(" 1 "), 3, " 9 ");
  const Case cases[] = {
      {"truncated", bytes.substr(0, bytes.size() - 5), "truncated: 59 of 64 bytes"},
      {"flipped", flipped, "checksum mismatch"},
      {"empty", "", "no cache header"},
      {"foreign", "#!/bin/sh\necho not a cache\n", "not a shimmer cache file"},
      {"future", future, "cache format 9, expected 1"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path p = dir / (std::string(c.name) + ".spv");
    Overwrite(p, c.content);
    Read r = ReadCapturingWarnings(p, "spirv");
    EXPECT_FALSE(r.payload);
    EXPECT_EQ(r.warnings, "shimmer: warning: ignoring the kernel cache file " + p.string() + " (" + c.reason +
                              "); it will be rebuilt\n");
  }
  Read wrong_kind = ReadCapturingWarnings(good, "vulkan-pipeline-cache");
  EXPECT_FALSE(wrong_kind.payload);
  EXPECT_NE(wrong_kind.warnings.find("holds 'spirv', expected 'vulkan-pipeline-cache'"), std::string::npos)
      << wrong_kind.warnings;
  // Each problem is said once per process, however often the file is read.
  Read again = ReadCapturingWarnings(dir / "flipped.spv", "spirv");
  EXPECT_FALSE(again.payload);
  EXPECT_EQ(again.warnings, "");
}

TEST(KernelCache, TrimRemovesTheOldestFilesFirst) {
  TempDir dir;
  const auto now = fs::file_time_type::clock::now();
  for (int i = 0; i < 5; ++i) {
    const fs::path p = dir / ("f" + std::to_string(i));
    Overwrite(p, std::string(100, 'a'));
    fs::last_write_time(p, now - std::chrono::hours(10 - i));  // f0 oldest
  }
  TrimCacheFolder(dir.path(), 300);
  EXPECT_EQ(dir.Names(), (std::vector<std::string>{"f2", "f3", "f4"}));
  TrimCacheFolder(dir.path(), 300);  // within the limit: nothing more goes
  EXPECT_EQ(dir.Names().size(), 3u);
  TrimCacheFolder(dir / "absent", 0);  // no folder: nothing to do, no error
}

TEST(KernelCache, UnwritableFolderIsAWarningNotAFailure) {
  TempDir dir;
  Overwrite(dir / "file", "x");  // a file where the folder should be
  ::testing::internal::CaptureStderr();
  WriteCacheFile(dir / "file" / "a.spv", "spirv", "payload");
  const std::string warnings = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(warnings.find("shimmer: warning: cannot keep compiled kernels in " + (dir / "file").string()),
            std::string::npos)
      << warnings;
}

// Sets an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value)
      ::setenv(name, value, 1);
    else
      ::unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      ::setenv(name_, old_->c_str(), 1);
    else
      ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(KernelCache, FolderFollowsXdgCacheHomeThenHomeAndCanBeTurnedOff) {
  {
    ScopedEnv off("SHIMMER_CACHE", nullptr), xdg("XDG_CACHE_HOME", "/x/cache"), home("HOME", "/h");
    EXPECT_EQ(KernelCacheDirectory(), fs::path("/x/cache/shimmer"));
  }
  {
    ScopedEnv off("SHIMMER_CACHE", nullptr), xdg("XDG_CACHE_HOME", ""), home("HOME", "/h");
    EXPECT_EQ(KernelCacheDirectory(), fs::path("/h/.cache/shimmer"));
  }
  {
    ScopedEnv off("SHIMMER_CACHE", nullptr), xdg("XDG_CACHE_HOME", nullptr), home("HOME", nullptr);
    EXPECT_FALSE(KernelCacheDirectory());
  }
  {
    ScopedEnv off("SHIMMER_CACHE", "off"), xdg("XDG_CACHE_HOME", "/x/cache");
    EXPECT_FALSE(KernelCacheDirectory());
  }
}

// The Vulkan pipeline cache checks the header of the data it is handed
// (vendor, device, pipelineCacheUUID) itself: the spec lets drivers assume
// valid data.
TEST(GpuVkPipelineCache, RefusesDataOfAnotherDeviceOrDriverBuild) {
  auto ctx = vk::Context::Create({});
  ASSERT_TRUE(ctx) << ctx.error();
  vk::Context& c = **ctx;
  auto empty = c.CreatePipelineCache();
  ASSERT_TRUE(empty) << empty.error();
  auto own = c.PipelineCacheData(**empty);
  ASSERT_TRUE(own) << own.error();
  ASSERT_GE(own->size(), 32u);  // at least VkPipelineCacheHeaderVersionOne
  EXPECT_TRUE(c.CreatePipelineCache(*own));

  auto with_word = [&](std::size_t offset, std::uint32_t value) {
    std::string data = *own;
    std::memcpy(data.data() + offset, &value, sizeof value);
    return data;
  };
  auto refused = [&](const std::string& data) {
    auto r = c.CreatePipelineCache(data);
    return r ? std::string("accepted") : r.error();
  };
  // headerSize, headerVersion, vendorID, deviceID, then the 16-byte UUID.
  EXPECT_EQ(refused(with_word(8, c.device().vendor_id + 1)), "written for another device");
  EXPECT_EQ(refused(with_word(12, c.device().device_id + 1)), "written for another device");
  std::string other_build = *own;
  other_build[16] = static_cast<char>(other_build[16] ^ 0x5a);
  EXPECT_EQ(refused(other_build), "written by another driver build");
  EXPECT_EQ(refused(with_word(4, 7)), "not a Vulkan pipeline cache");
  EXPECT_EQ(refused(with_word(0, 4096)), "not a Vulkan pipeline cache");  // header larger than the data
  EXPECT_EQ(refused(own->substr(0, 10)), "truncated: 10 bytes, shorter than a cache header");

  // A pipeline made through a cache works like one made without.
  auto spirv = shading::CompileCompute({"write_one.comp", R"(#version 450
layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer Out { uint value[]; };
void main() { value[0] = 7u; }
)"});
  ASSERT_TRUE(spirv) << spirv.error();
  const vk::BufferKind kinds[] = {vk::BufferKind::kStorage};
  auto pipeline = c.CreatePipeline(*spirv, {}, kinds, 0, empty->get());
  ASSERT_TRUE(pipeline) << pipeline.error();
  auto out = c.CreateBuffer(16);
  ASSERT_TRUE(out) << out.error();
  vk::Buffer* buffers[] = {out->get()};
  ASSERT_TRUE(c.Dispatch(**pipeline, buffers, {}, 1, 1));
  std::uint32_t value = 0;
  std::memcpy(&value, (*out)->data(), sizeof value);
  EXPECT_EQ(value, 7u);
}

std::vector<fs::path> FilesUnder(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::exists(dir)) return files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  return files;
}

TEST(GpuCli, SecondRenderUsesTheKernelCacheAndADamagedOneIsRebuilt) {
  TempDir dir;
  const std::string env = "XDG_RUNTIME_DIR=/tmp XDG_CACHE_HOME=" + (dir / "cache").string();
  // A variant and size no other test renders: this process's kernel is not in
  // any other test's cache either way.
  auto render = [&](const std::string& out, const std::string& extra_env = "") {
    return shimmer::testing::RunShimmer(
        SHIMMER_CLI, "render --scene wires --variant vlachos15 --frames 1 --size 24 16 --out " + (dir / out).string(),
        env + " " + extra_env);
  };
  auto first = render("a");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_EQ(first.output.find("warning"), std::string::npos) << first.output;
  const fs::path shimmer_cache = dir / "cache" / "shimmer";
  const auto kernels = FilesUnder(shimmer_cache / "spirv"), specialized = FilesUnder(shimmer_cache / "specialized");
  ASSERT_EQ(kernels.size(), 1u);
  ASSERT_EQ(specialized.size(), 1u);

  auto second = render("b");
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_EQ(second.output.find("warning"), std::string::npos) << second.output;
  EXPECT_EQ(ReadAll(dir / "b" / "frame_0000.exr"), ReadAll(dir / "a" / "frame_0000.exr"));
  EXPECT_EQ(FilesUnder(shimmer_cache).size(), 2u);  // found, not compiled again under another name

  // Damage both modules: the render warns about each, rebuilds it and draws
  // the same pixels; the next render finds them whole again.
  const std::string kernel_bytes = ReadAll(kernels[0]);
  Overwrite(kernels[0], kernel_bytes.substr(0, kernel_bytes.size() / 2));
  std::string spec_bytes = ReadAll(specialized[0]);
  spec_bytes[spec_bytes.size() - 3] ^= 0x10;
  Overwrite(specialized[0], spec_bytes);
  auto damaged = render("c");
  ASSERT_EQ(damaged.exit_code, 0) << damaged.output;
  EXPECT_NE(damaged.output.find("ignoring the kernel cache file " + kernels[0].string() + " (truncated"),
            std::string::npos)
      << damaged.output;
  EXPECT_NE(damaged.output.find("ignoring the kernel cache file " + specialized[0].string() + " (checksum mismatch)"),
            std::string::npos)
      << damaged.output;
  EXPECT_EQ(ReadAll(dir / "c" / "frame_0000.exr"), ReadAll(dir / "a" / "frame_0000.exr"));
  EXPECT_EQ(ReadAll(kernels[0]), kernel_bytes);
  auto healed = render("d");
  ASSERT_EQ(healed.exit_code, 0) << healed.output;
  EXPECT_EQ(healed.output.find("warning"), std::string::npos) << healed.output;

  // SHIMMER_CACHE=off: nothing read, nothing written.
  fs::remove_all(dir / "cache");
  auto off = render("e", "SHIMMER_CACHE=off");
  ASSERT_EQ(off.exit_code, 0) << off.output;
  EXPECT_FALSE(fs::exists(shimmer_cache));
  EXPECT_EQ(ReadAll(dir / "e" / "frame_0000.exr"), ReadAll(dir / "a" / "frame_0000.exr"));
}

}  // namespace
}  // namespace shimmer::render
