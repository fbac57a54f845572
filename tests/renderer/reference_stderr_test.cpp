// The reference's standard error against the truth it claims: renders of one
// frame with independent seeds scatter by as much as stderr.Y predicts. Also
// the replicate count, the adaptive reference's unconverged pixels and the
// validation of K.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "cli_run.h"
#include "shimmer/core/sequence_file.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::render {
namespace {

namespace fs = std::filesystem;

RenderSettings Reference(const std::string& scene_name, const std::string& material, int n, int size) {
  RenderSettings s;
  s.scene = scene::LoadScene(scene_name).value();
  s.material = scene::ParseMaterial(material, s.scene.material).value();
  s.derivatives = shading::DerivativeSource::kAnalytic;
  s.width = size;
  s.height = size;
  s.frames = 1;
  s.reference_spp = n;
  return s;
}

double PixelLuminance(const Frame& f, int x, int y) {
  return 0.2126 * f.at(kBeautyR, x, y) + 0.7152 * f.at(kBeautyR + 1, x, y) + 0.0722 * f.at(kBeautyR + 2, x, y);
}

struct Agreement {
  double predicted_se = 0;  // RMS over pixels of stderr.Y
  double empirical_se = 0;  // RMS over pixels of the spread across seeds
  int pixels = 0;
};

// Renders one frame `renders` times with different seeds; per pixel the
// variance of its luminance across renders (unbiased) against the mean of
// the variances stderr.Y^2 that each render predicted for itself.
Agreement MeasureAgreement(const RenderSettings& base, int renders) {
  const int w = base.width, h = base.height;
  std::vector<double> sum(w * h), sum2(w * h), predicted(w * h);
  for (int m = 0; m < renders; ++m) {
    RenderSettings s = base;
    s.seed = 1000 + m;
    auto r = Renderer::Create(s);
    EXPECT_TRUE(r) << r.error();
    if (!r) return {};
    auto f = (*r)->RenderFrame(0);
    EXPECT_TRUE(f) << f.error();
    if (!f) return {};
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double lum = PixelLuminance(*f, x, y), se = f->at(kStderr, x, y);
        sum[y * w + x] += lum;
        sum2[y * w + x] += lum * lum;
        predicted[y * w + x] += se * se / renders;
      }
  }
  Agreement a;
  double predicted_sum = 0, empirical_sum = 0;
  for (int i = 0; i < w * h; ++i) {
    const double mean = sum[i] / renders;
    const double empirical = std::max(0.0, (sum2[i] - renders * mean * mean) / (renders - 1));
    // Pixels where neither sees any noise (background, flat lit surface) say nothing.
    const double negligible = 1e-12 * std::max(mean * mean, 1e-4);
    if (predicted[i] <= negligible && empirical <= negligible) continue;
    predicted_sum += predicted[i];
    empirical_sum += empirical;
    ++a.pixels;
  }
  if (a.pixels == 0) return a;
  a.predicted_se = std::sqrt(predicted_sum / a.pixels);
  a.empirical_se = std::sqrt(empirical_sum / a.pixels);
  return a;
}

// The i.i.d. formula over all N x N samples overstated this 2-27x; the spread
// of independent replicates must be right within 25 %.
TEST(GpuReferenceStderr, PredictsTheSpreadOfIndependentRenders) {
  for (int n : {4, 8}) {
    SCOPED_TRACE("N = " + std::to_string(n));
    const Agreement a = MeasureAgreement(Reference("sphere-field", "ggx:0.05", n, 48), 16);
    ASSERT_GT(a.pixels, 100);
    const double ratio = a.predicted_se / a.empirical_se;
    std::printf("N = %d: RMS predicted SE %.4g, empirical %.4g over %d pixels: ratio %.3f\n", n, a.predicted_se,
                a.empirical_se, a.pixels, ratio);
    EXPECT_GT(ratio, 0.75);
    EXPECT_LT(ratio, 1.25);
  }
}

TEST(GpuReferenceStderr, FixedReferenceIsKReplicatesOfNxN) {
  RenderSettings s = Reference("sphere", "ggx:0.1", 3, 16);
  s.reference_replicates = 5;
  auto r = Renderer::Create(s);
  ASSERT_TRUE(r) << r.error();
  auto f = (*r)->RenderFrame(0);
  ASSERT_TRUE(f) << f.error();
  EXPECT_EQ(f->rounds, 5);
  EXPECT_EQ(f->at(kSampleCount, 8, 8), 45.0f);
  EXPECT_DOUBLE_EQ(f->mean_spp, 45.0);
  EXPECT_EQ(f->unconverged_pixels, 0);
}

TEST(GpuReferenceStderr, SeedsGiveIndependentRendersOfTheSameFrame) {
  RenderSettings s = Reference("sphere", "ggx:0.05", 2, 16);
  auto render = [&](std::uint32_t seed) {
    s.seed = seed;
    auto r = Renderer::Create(s);
    EXPECT_TRUE(r) << r.error();
    return r ? (*r)->RenderFrame(0).value() : Frame{};
  };
  const Frame a = render(0), b = render(0), c = render(7);
  int same = 0, differing = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      same += PixelLuminance(a, x, y) == PixelLuminance(b, x, y);
      differing += PixelLuminance(a, x, y) != PixelLuminance(c, x, y);
    }
  EXPECT_EQ(same, 256);
  EXPECT_GT(differing, 10);
}

// A tolerance no pixel reaches: the render stops at max_rounds, and
// sequence.json and the CLI say how many pixels stayed above it.
TEST(GpuReferenceStderr, AdaptiveRecordsUnconvergedPixels) {
  const fs::path dir = fs::temp_directory_path() / "shimmer_reference_unconverged_test";
  fs::remove_all(dir);
  RenderSettings s = Reference("sphere-field", "ggx:0.05", 2, 16);
  s.frames = 2;
  s.reference_replicates = 2;
  s.reference_tolerance = 1e-6;
  s.max_rounds = 3;
  auto rendered = RenderSequence(s, dir.string(), nullptr);
  ASSERT_TRUE(rendered) << rendered.error();
  auto seq = ReadSequenceFile(dir / "sequence.json");
  ASSERT_TRUE(seq) << seq.error();
  EXPECT_EQ(seq->reference_replicates, 2);
  ASSERT_EQ(seq->frames.size(), 2u);
  for (const SequenceFrame& f : seq->frames) {
    EXPECT_EQ(f.rounds, 3);
    ASSERT_TRUE(f.unconverged_pixels);
    EXPECT_GT(*f.unconverged_pixels, 10);
    EXPECT_LE(*f.unconverged_pixels, 256);
  }
  fs::remove_all(dir);

  const shimmer::testing::CliRun run = shimmer::testing::RunShimmer(
      SHIMMER_CLI,
      "render --scene sphere-field --frames 2 --size 16 16 --reference-spp 2 --reference-replicates 2 "
      "--reference-tolerance 1e-6 --max-rounds 3 --out " +
          dir.string(),
      "XDG_RUNTIME_DIR=/tmp");
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("shimmer: warning: "), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("in 2 of 2 frames stayed above --reference-tolerance 1e-06 at --max-rounds 3"),
            std::string::npos)
      << run.output;
  std::ifstream in(dir / "sequence.json");
  const auto json = nlohmann::json::parse(in);
  EXPECT_EQ(json["reference_replicates"], 2);
  EXPECT_GT(json["frames"][0]["unconverged_pixels"].get<int>(), 10);
  fs::remove_all(dir);
}

TEST(GpuReferenceStderr, ReplicatesOutsideTheirBoundsAreRefused) {
  for (int k : {1, 0, kMaxRounds + 1}) {
    RenderSettings s = Reference("sphere", "ggx:0.1", 4, 16);
    s.reference_replicates = k;
    const Status status = ValidateSettings(s);
    ASSERT_FALSE(status) << k;
    EXPECT_NE(status.error().find("reference_replicates must be in 2..4096"), std::string::npos) << status.error();
  }
  const fs::path dir = fs::temp_directory_path() / "shimmer_reference_replicates_test";
  fs::remove_all(dir);
  const shimmer::testing::CliRun run = shimmer::testing::RunShimmer(
      SHIMMER_CLI, "render --frames 1 --size 16 16 --reference-spp 2 --reference-replicates 1 --out " + dir.string(),
      "XDG_RUNTIME_DIR=/tmp");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("shimmer: error: --reference-replicates must be in 2..4096"), std::string::npos)
      << run.output;
  EXPECT_FALSE(fs::exists(dir));
}

}  // namespace
}  // namespace shimmer::render
