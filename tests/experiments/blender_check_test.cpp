// shimmer's reference against Blender Cycles (label external): the same shot
// rendered by `shimmer render --reference-spp` and by the script of `shimmer
// export-blender`, compared in total energy and per pixel. Skipped when
// `blender` is not on PATH.
//
// The one known difference in the models is the Smith masking: Cycles uses
// the separable G1(v) G1(l), shimmer the height-correlated G2, whose ratio
// (1 + Lo + Li) / (1 + Lo + Li + Lo Li) departs from 1 only where the view or
// the light is grazing. Pixels where it departs by more than kRimTolerance at
// the pixel centre, or next to such a pixel or to the silhouette, are left out
// of the per-pixel check (not of the energy).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "shimmer/core/exr_input.h"
#include "shimmer/renderer/scene.h"

namespace shimmer {
namespace {

namespace fs = std::filesystem;

constexpr int kSize = 64;
constexpr int kShimmerSppN = 32;  // 32 x 32 stratified samples a pixel
constexpr int kCyclesSpp = 512;   // each of two renders with different seeds
constexpr double kRimTolerance = 0.002;

bool BlenderOnPath() { return std::system("command -v blender >/dev/null 2>&1") == 0; }

int Shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ReadAll(const fs::path& file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Planes of the named channels, in order.
std::vector<std::vector<float>> ReadChannels(const fs::path& file, const std::vector<std::string>& names) {
  std::vector<std::vector<float>> planes(names.size(), std::vector<float>(kSize * kSize));
  auto input = ExrInput::Open(file);
  EXPECT_TRUE(input) << input.error();
  if (!input) return planes;
  EXPECT_EQ(input->parts()[0].width, kSize);
  EXPECT_EQ(input->parts()[0].height, kSize);
  std::vector<ExrPlaneRequest> requests;
  for (std::size_t i = 0; i < names.size(); ++i) requests.push_back({names[i], planes[i].data()});
  const Status read = input->Read(0, requests);
  EXPECT_TRUE(read) << read.error();
  return planes;
}

std::vector<double> Luminance(const std::vector<std::vector<float>>& rgb, std::size_t first) {
  std::vector<double> y(kSize * kSize);
  for (std::size_t i = 0; i < y.size(); ++i)
    y[i] = 0.2126 * rgb[first][i] + 0.7152 * rgb[first + 1][i] + 0.0722 * rgb[first + 2][i];
  return y;
}

double GgxLambda(double cos_theta, double alpha) {
  const double c2 = std::max(cos_theta * cos_theta, 1e-12);
  return (std::sqrt(1 + alpha * alpha * (1 - c2) / c2) - 1) / 2;
}

struct Comparison {
  double energy_ratio = 0;  // Cycles / shimmer, all pixels
  int compared = 0;         // pixels in the per-pixel check
  int within_3_sigma = 0;
  double mean_abs_rel = 0;  // mean |C - S| / S over compared pixels with S > 1 % of the peak
  int rim = 0;              // pixels left out
};

Comparison Compare(const std::string& scene_name, const std::string& material, const fs::path& dir) {
  const std::string shimmer = SHIMMER_EXE;
  const std::string shot = scene_name + " --material " + material + " --camera orbit --frames 1 --size " +
                           std::to_string(kSize) + " " + std::to_string(kSize);
  const std::string log = " >>" + (dir / "log.txt").string() + " 2>&1";
  EXPECT_EQ(Shell(shimmer + " render --scene " + shot + " --reference-spp " + std::to_string(kShimmerSppN) + " --out " +
                  (dir / "ref").string() + log),
            0)
      << ReadAll(dir / "log.txt");
  EXPECT_EQ(Shell(shimmer + " export-blender " + shot + " -o " + (dir / "scene.py").string() + log), 0)
      << ReadAll(dir / "log.txt");
  for (int seed : {1, 2})
    EXPECT_EQ(Shell("blender -b --factory-startup -P " + (dir / "scene.py").string() + " -- --out " +
                    (dir / ("cycles" + std::to_string(seed) + ".exr")).string() + " --spp " +
                    std::to_string(kCyclesSpp) + " --threads 2 --seed " + std::to_string(seed) + log),
              0)
        << ReadAll(dir / "log.txt");

  const auto ref = ReadChannels(dir / "ref" / "frame_0000.exr",
                                {"R", "G", "B", "stderr.Y", "depth.Z", "normal.X", "normal.Y", "normal.Z"});
  const auto c1 = Luminance(ReadChannels(dir / "cycles1.exr", {"R", "G", "B"}), 0);
  const auto c2 = Luminance(ReadChannels(dir / "cycles2.exr", {"R", "G", "B"}), 0);
  const auto s = Luminance(ref, 0);

  // The Smith ratio at each pixel centre, from shimmer's own AOVs.
  const scene::Scene sc = scene::LoadScene(scene_name).value();
  const double alpha = scene::ParseMaterial(material, sc.material).value().alpha.x;
  const shading::CameraDesc cam = scene::CameraAt(scene::CameraPath::kOrbit, sc.rig, 0, 30, kSize, kSize);
  std::vector<bool> rim(kSize * kSize, false);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const int i = y * kSize + x;
      const double sx = cam.tan_half_fov_y * double(kSize) / kSize, sy = cam.tan_half_fov_y;
      const glm::dvec3 d = glm::normalize(cam.fwd + cam.right * ((2.0 * (x + 0.5) / kSize - 1) * sx) +
                                          cam.up * ((1 - 2.0 * (y + 0.5) / kSize) * sy));
      bool grazing = true;  // a centre that misses: the silhouette
      if (ref[4][i] > 0) {
        const glm::dvec3 n{ref[5][i], ref[6][i], ref[7][i]};
        const glm::dvec3 p = cam.pos + d * double(ref[4][i]);
        const glm::dvec3 l =
            sc.light.type == shading::LightType::kDirectional ? sc.light.vec : glm::normalize(sc.light.vec - p);
        const double lo = GgxLambda(glm::dot(-d, n), alpha), li = GgxLambda(glm::dot(l, n), alpha);
        grazing = glm::dot(l, n) > 0 && 1 - (1 + lo + li) / (1 + lo + li + lo * li) > kRimTolerance;
        if (glm::dot(l, n) <= 0) grazing = false;
      } else if (s[i] == 0 && c1[i] == 0 && c2[i] == 0) {
        grazing = false;  // background
      }
      if (!grazing) continue;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (x + dx >= 0 && x + dx < kSize && y + dy >= 0 && y + dy < kSize) rim[(y + dy) * kSize + x + dx] = true;
    }

  Comparison out;
  double es = 0, ec = 0, peak = 0;
  for (std::size_t i = 0; i < s.size(); ++i) peak = std::max(peak, s[i]);
  int relative_count = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double c = (c1[i] + c2[i]) / 2;
    es += s[i];
    ec += c;
    if (rim[i]) {
      ++out.rim;
      continue;
    }
    // Var of the mean of two renders, from their difference (one degree of
    // freedom a pixel; a floor of 0.1 % of the peak keeps a lucky zero from
    // making the check exact).
    const double var_c = (c1[i] - c2[i]) * (c1[i] - c2[i]) / 4;
    const double sigma = std::sqrt(double(ref[3][i]) * ref[3][i] + var_c) + 1e-3 * peak;
    ++out.compared;
    if (std::abs(c - s[i]) <= 3 * sigma) ++out.within_3_sigma;
    if (s[i] > 0.01 * peak) {
      out.mean_abs_rel += std::abs(c - s[i]) / s[i];
      ++relative_count;
    }
  }
  out.energy_ratio = ec / es;
  out.mean_abs_rel /= std::max(relative_count, 1);
  std::printf(
      "%s %s: energy Cycles/shimmer %.5f; %d of %d pixels within 3 sigma (%d rim pixels left out); "
      "mean |C-S|/S %.4f\n",
      scene_name.c_str(), material.c_str(), out.energy_ratio, out.within_3_sigma, out.compared, out.rim,
      out.mean_abs_rel);
  return out;
}

class BlenderCheck : public ::testing::TestWithParam<std::string> {};

TEST_P(BlenderCheck, CyclesAgreesWithTheReference) {
  if (!BlenderOnPath())
    GTEST_SKIP() << "blender is not on PATH: the Cycles check needs Blender (apt-get install blender)";
  const fs::path dir = fs::temp_directory_path() / ("shimmer-blender-" + std::to_string(::getpid()) + "-" +
                                                    ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Comparison c = Compare("sphere", GetParam(), dir);
  EXPECT_NEAR(c.energy_ratio, 1.0, 0.005);
  EXPECT_GT(c.compared, kSize * kSize / 2);
  // 3 sigma holds for 99.7 % of Gaussian errors; the one-sample variance
  // estimate of Cycles' noise has heavier tails, hence 98 %.
  EXPECT_GE(c.within_3_sigma, 0.98 * c.compared);
  if (!HasFailure()) fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(
    Sphere, BlenderCheck,
    ::testing::Values("ggx:0.2,f0=1,albedo=0", "ggx:0.05,f0=1,albedo=0", "ggx:0.2,f0=0.04,albedo=0.5"),
    [](const ::testing::TestParamInfo<std::string>& info) {
      return std::string(info.index == 0 ? "Alpha0_2" : info.index == 1 ? "Alpha0_05" : "Alpha0_2FresnelDiffuse");
    });

}  // namespace
}  // namespace shimmer
