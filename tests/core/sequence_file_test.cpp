#include "shimmer/core/sequence_file.h"

#include <gtest/gtest.h>

#include "temp_dir.h"

namespace shimmer {
namespace {

SequenceFile Example() {
  SequenceFile s;
  s.status = SequenceStatus::kFailed;
  s.error = "frame 2: device lost";
  s.scene = "wires";
  s.material = "ggx:0.05,f0=0.04,albedo=0.5";
  s.light = "directional";
  s.variant = "tk19";
  s.derivatives = "quad";
  s.camera = {"orbit", {0, 0.5, 0}, 4, 15, 30, 30};
  s.params = {{"kappa", 0.18}, {"sigma2", 0.25}};
  s.width = 64;
  s.height = 32;
  s.fps = 24;
  s.frame_count = 3;
  s.spp = 16;
  s.reference = true;
  s.reference_spp = 4;
  s.reference_replicates = 4;
  s.reference_tolerance = 0.01;
  s.seed = 4000000000u;
  s.reference_luminance_floor = 0.01;
  s.device = "llvmpipe";
  s.driver = "llvmpipe Mesa";
  s.revision = "abc";
  s.timings.render_wall_ms = 12.5;
  s.frames = {{"frame_0000.exr", 1.5, 0, 64.0, 4, 0}, {"frame_0001.exr", 2.5, 1 / 24.0, 80.0, 5, 12}};
  return s;
}

// The one writer and the one reader agree on every field.
TEST(SequenceFile, WrittenAndReadBackEqual) {
  testing::TempDir dir;
  ASSERT_TRUE(WriteSequenceFile(dir / "sequence.json", Example()));
  auto back = ReadSequenceFile(dir / "sequence.json");
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(ToJson(*back), ToJson(Example()));
  EXPECT_EQ(back->status, SequenceStatus::kFailed);
  EXPECT_DOUBLE_EQ(back->MeanGpuMs(), 2.0);
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"sequence.json"});
}

// Another renderer's minimal sidecar: only fps and file names.
TEST(SequenceFile, MinimalForeignSidecarReads) {
  auto s = SequenceFromJson(nlohmann::json::parse(R"({"fps": 24, "frames": ["b.exr", {"file": "a.exr"}]})"), "s.json");
  ASSERT_TRUE(s) << s.error();
  EXPECT_EQ(s->status, SequenceStatus::kComplete);
  EXPECT_EQ(*s->fps, 24);
  ASSERT_EQ(s->frames.size(), 2u);
  EXPECT_EQ(s->frames[1].file, "a.exr");
}

TEST(SequenceFile, WrongTypesNameTheKey) {
  struct Case {
    const char* json;
    const char* expect;
  };
  for (const Case& c :
       {Case{R"({"fps": "fast"})", "s.json: \"fps\" must be a finite number"},
        Case{R"({"fps": -1})", "s.json: \"fps\" must be > 0"},
        Case{R"({"status": "done"})", "\"status\" must be \"running\", \"complete\" or \"failed\""},
        Case{R"({"frames": [{"gpu_ms": 1}]})", "\"frames\" must be an array of file names"},
        Case{R"({"frames": [{"file": "a.exr", "gpu_ms": "x"}]})", "frames[0]: \"gpu_ms\""},
        Case{R"({"camera": {"target": [1, 2]}})", "camera: \"target\" must be [x, y, z]"},
        Case{R"({"frames": [{"file": "a.exr", "unconverged_pixels": 0.5}]})", "frames[0]: \"unconverged_pixels\""},
        Case{R"({"seed": -1})", "\"seed\" must be an integer in 0..4294967295"},
        Case{R"({"width": 1.5})", "\"width\" must be an integer"}, Case{R"([1, 2])", "expected a JSON object"}}) {
    auto s = SequenceFromJson(nlohmann::json::parse(c.json), "s.json");
    ASSERT_FALSE(s) << c.json;
    EXPECT_NE(s.error().find(c.expect), std::string::npos) << s.error();
  }
}

}  // namespace
}  // namespace shimmer
