// Golden frames of the generated mesh shots (experiments/scenes): frame 0 of
// `none` at 48 x 48 compared with results/tests/golden/SCENE.exr, or, with
// SHIMMER_UPDATE_GOLDEN=1, written there (Filament's compare/update modes).
// A changed loader, BVH, attribute interpolation or material mapping shows
// here as a changed picture, named by the scene; the tolerance allows
// another device's float rounding (a few pixels near silhouettes and
// triangle edges), not a changed image.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "shimmer/core/exr_input.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::render {
namespace {

namespace fs = std::filesystem;

bool Updating() {
  const char* update = std::getenv("SHIMMER_UPDATE_GOLDEN");
  return update && *update && std::string(update) != "0";
}

class GpuGolden : public ::testing::TestWithParam<const char*> {};

TEST_P(GpuGolden, GeneratedShotFrameZero) {
  const std::string name = GetParam();
  RenderSettings s;
  auto scene = scene::LoadScene(std::string(SHIMMER_SOURCE_DIR) + "/experiments/scenes/" + name + ".json");
  ASSERT_TRUE(scene) << scene.error();
  s.scene = *scene;
  s.material = s.scene.material;
  s.variant = "none";
  s.derivatives = shading::DerivativeSource::kQuadFine;
  s.width = s.height = 48;
  s.frames = 1;
  auto r = Renderer::Create(s);
  ASSERT_TRUE(r) << r.error();
  auto frame = (*r)->RenderFrame(0);
  ASSERT_TRUE(frame) << frame.error();
  const fs::path golden = fs::path(SHIMMER_SOURCE_DIR) / "results" / "tests" / "golden" / (name + ".exr");
  if (Updating()) {
    fs::create_directories(golden.parent_path());
    ASSERT_TRUE(WriteFrameExr(golden.string(), *frame, false).ok());
    return;
  }
  auto in = ExrInput::Open(golden);
  ASSERT_TRUE(in) << in.error() << " (run this test with SHIMMER_UPDATE_GOLDEN=1 to write it)";
  const std::size_t n = std::size_t(48) * 48;
  std::vector<float> want(3 * n);
  const char* channels[] = {"R", "G", "B"};
  std::vector<ExrPlaneRequest> requests;
  for (int c = 0; c < 3; ++c) requests.push_back({channels[c], want.data() + c * n});
  ASSERT_TRUE(in->Read(0, requests).ok());
  int differ = 0, lit = 0;
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x) {
        const double g = frame->at(kBeautyR + c, x, y), w = want[c * n + y * 48 + x];
        lit += c == 1 && w > 1e-3;
        differ += std::abs(g - w) > 2e-2 * std::abs(w) + 1e-3;
      }
  EXPECT_GT(lit, 10) << name << ": the golden frame shows almost nothing";
  EXPECT_LE(differ, int(3 * n / 100)) << name << ": " << differ << " of " << 3 * n
                                      << " channel values differ from " << golden
                                      << "; if the change is meant, rerun with SHIMMER_UPDATE_GOLDEN=1 and commit it";
}

INSTANTIATE_TEST_SUITE_P(GpuMeshShots, GpuGolden,
                         ::testing::Values("torus-lowpoly", "torus-fine", "panel", "cable", "tk19-fig1"));

}  // namespace
}  // namespace shimmer::render
