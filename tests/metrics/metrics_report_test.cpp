// Known-answer tests of the whole streaming pass on sequences generated here.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "shimmer/metrics/flicker_spectrum.h"
#include "shimmer/metrics/metrics_report.h"
#include "test_sequences.h"

namespace shimmer::metrics {
namespace {

using testing::Layout;
using testing::SequenceSpec;
using testing::TempDir;
using testing::WriteExrMats;
using testing::WriteSequence;

constexpr double kPi = std::numbers::pi;

SequenceSpec Spec(int frames, testing::PixelFunction f, int size = 32) {
  SequenceSpec s;
  s.frames = frames;
  s.width = s.height = size;
  s.value = std::move(f);
  return s;
}

MetricsReport Measure(const MetricsOptions& options) {
  auto report = ComputeMetrics(options);
  EXPECT_TRUE(report) << report.error();
  return report ? *report : MetricsReport{};
}

TEST(MetricsReport, ConstantSequencesHaveZeroVarianceAndZeroError) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(8, [](int, int x, int y) { return 0.01f * (x + 3 * y); }));
  WriteSequence(dir / "ref", Spec(8, [](int, int x, int y) { return 0.01f * (x + 3 * y); }));
  MetricsReport r = Measure({.test = dir / "test", .reference = dir / "ref"});
  EXPECT_EQ(r.frames, 8);
  EXPECT_EQ(r.pixels, 32 * 32);
  EXPECT_EQ(r.tv_test, 0.0);
  EXPECT_EQ(*r.tv_ref, 0.0);
  EXPECT_EQ(*r.tv_err, 0.0);
  EXPECT_FALSE(r.tv_ratio);  // 0 / 0: reported as undefined, not NaN
  EXPECT_EQ(*r.energy_bias, 0.0);
  EXPECT_EQ(*r.rmse, 0.0);
  EXPECT_EQ(*r.relmse, 0.0);
  EXPECT_EQ(*r.temporal_diff_err, 0.0);
  EXPECT_EQ(r.temporal_diff_test, 0.0);
  EXPECT_EQ(r.nan_pixels, 0);
  for (double p : r.flicker.psd) EXPECT_EQ(p, 0.0);
  EXPECT_EQ(r.flicker.flicker_index, 0.0);
}

// T_t(p) = c + A sin(2 pi f t / fs + phase(p)), f on a Welch bin: the sample
// variance over whole periods is A^2/2 N/(N-1) at every pixel; the error against
// a constant reference is the same sinusoid; its PSD peaks in bin f L / fs.
TEST(MetricsReport, PixelSinusoidHasKnownVarianceAndSpectralPeak) {
  const int frames = 64, length = 32, k0 = 6;
  const double fs = 48, amplitude = 0.3, f0 = k0 * fs / length;  // 9 Hz
  TempDir dir;
  WriteSequence(dir / "test", Spec(frames, [&](int t, int x, int y) {
                  return static_cast<float>(2.0 + amplitude * std::sin(2 * kPi * f0 * t / fs + 0.1 * (x + y)));
                }));
  WriteSequence(dir / "ref", Spec(frames, [](int, int, int) { return 2.0f; }));
  MetricsReport r =
      Measure({.test = dir / "test", .reference = dir / "ref", .request = {.fps = fs}, .segment_length = length});
  const double variance = amplitude * amplitude / 2 * frames / (frames - 1.0);
  EXPECT_NEAR(r.tv_test, variance, 1e-6 * variance);
  EXPECT_NEAR(*r.tv_err, variance, 1e-6 * variance);
  EXPECT_EQ(*r.tv_ref, 0.0);
  EXPECT_NEAR(*r.energy_bias, 0.0, 1e-7);  // whole periods: no net energy
  EXPECT_EQ(r.fps, fs);
  EXPECT_EQ(r.flicker.signal, "error");
  EXPECT_EQ(r.flicker.segments, WelchSegmentCount(frames, length));
  const auto& psd = r.flicker.psd;
  const size_t peak = std::max_element(psd.begin(), psd.end()) - psd.begin();
  EXPECT_EQ(peak, static_cast<size_t>(k0));
  EXPECT_DOUBLE_EQ(r.flicker.freq_hz[peak], f0);
  const double a2 = amplitude * amplitude;
  EXPECT_NEAR(psd[k0], a2 * length / (3 * fs), 1e-5 * a2 * length / fs);
  // 9 Hz is in the [8, fs/2] band, and that band holds the whole variance A^2/2.
  EXPECT_NEAR(r.flicker.band_high, a2 / 2 - psd[5] * fs / length, 1e-6);
  EXPECT_NEAR(r.flicker.band_low + r.flicker.band_mid + r.flicker.band_high, a2 / 2, 1e-6);
  EXPECT_GT(r.flicker.flicker_index, 0.5 * a2 / 2);  // 9 Hz is near the eye's peak
}

TEST(MetricsReport, ConstantMultiplicativeBiasIsExact) {
  TempDir dir;
  const double gain = 0.8;  // a filter that loses 20% of the highlight's energy
  auto ref = [](int t, int x, int y) { return 0.5f + 0.25f * ((t + x + y) % 4); };
  WriteSequence(dir / "ref", Spec(6, ref));
  WriteSequence(dir / "test", Spec(6, [&](int t, int x, int y) { return static_cast<float>(gain * ref(t, x, y)); }));
  MetricsReport r = Measure({.test = dir / "test", .reference = dir / "ref"});
  EXPECT_NEAR(*r.energy_bias, gain - 1, 1e-7);
  ASSERT_EQ(r.energy_bias_per_frame.size(), 6u);
  for (double b : r.energy_bias_per_frame) EXPECT_NEAR(b, gain - 1, 1e-7);
  EXPECT_NEAR(r.energy_bias_map.at<float>(3, 4), gain - 1, 1e-6);
  EXPECT_NEAR(*r.tv_ratio, gain * gain, 1e-6);  // variance scales with the square
}

// relmse's split on sequences whose parts are known in closed form: a static
// reference R(x, y), and a test R + a(x, y) + b(x, y) s_t with s_t = ±1
// alternating (mean 0 over the even frame count). Each pixel's weight
// w = 1 / (R^2 + 0.01) is constant in time, so its weighted mean error is a
// and the parts are mean(w a^2) (spatial) and mean(w b^2) (temporal).
TEST(MetricsReport, JointErrorSplitsIntoKnownTemporalAndSpatialParts) {
  TempDir dir;
  auto ref = [](int, int x, int y) { return 0.25f + 0.03125f * ((x + 2 * y) % 8); };
  auto offset = [](int x, int y) { return 0.0625f * ((x * y) % 3); };  // spatial error
  auto swing = [](int x, int y) { return 0.03125f * ((x + y) % 4); };  // temporal error
  WriteSequence(dir / "ref", Spec(8, ref));
  WriteSequence(dir / "test", Spec(8, [&](int t, int x, int y) {
                  return ref(t, x, y) + offset(x, y) + (t % 2 ? -1.f : 1.f) * swing(x, y);
                }));
  double spatial = 0, temporal = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const double r = ref(0, x, y), w = 1 / (r * r + 0.01), a = offset(x, y), b = swing(x, y);
      spatial += w * a * a / 1024, temporal += w * b * b / 1024;
    }
  MetricsReport r = Measure({.test = dir / "test", .reference = dir / "ref"});
  ASSERT_TRUE(r.relmse_temporal && r.relmse_spatial && r.relmse);
  EXPECT_NEAR(*r.relmse_spatial, spatial, 1e-6 * spatial);
  EXPECT_NEAR(*r.relmse_temporal, temporal, 1e-6 * temporal);
  EXPECT_NEAR(*r.relmse_temporal + *r.relmse_spatial, *r.relmse, 1e-12 * *r.relmse);
  ASSERT_TRUE(r.ci95 && r.ci95->relmse_temporal && r.ci95->relmse_spatial);
  EXPECT_LE(r.ci95->relmse_temporal->lo, *r.relmse_temporal);
  EXPECT_GE(r.ci95->relmse_temporal->hi, *r.relmse_temporal);
  EXPECT_LE(r.ci95->relmse_spatial->lo, *r.relmse_spatial);
  EXPECT_GE(r.ci95->relmse_spatial->hi, *r.relmse_spatial);
}

// A pure offset has no temporal part, a pure zero-mean swing no spatial
// part; with a reference that moves, each pixel's mean error is weighted
// as its samples are, and the parts still add up to relmse.
TEST(MetricsReport, JointErrorOfAnOffsetIsAllSpatialAndOfASwingAllTemporal) {
  TempDir dir;
  auto ref = [](int, int x, int y) { return 0.5f + 0.0625f * ((x + y) % 4); };
  WriteSequence(dir / "ref", Spec(8, ref));
  WriteSequence(dir / "offset", Spec(8, [&](int t, int x, int y) { return ref(t, x, y) + 0.125f; }));
  WriteSequence(dir / "swing", Spec(8, [&](int t, int x, int y) { return ref(t, x, y) + (t % 2 ? -0.125f : 0.125f); }));
  const MetricsReport offset = Measure({.test = dir / "offset", .reference = dir / "ref"});
  EXPECT_NEAR(*offset.relmse_spatial, *offset.relmse, 1e-9 * *offset.relmse);
  EXPECT_NEAR(*offset.relmse_temporal, 0.0, 1e-12);
  const MetricsReport swing = Measure({.test = dir / "swing", .reference = dir / "ref"});
  EXPECT_NEAR(*swing.relmse_temporal, *swing.relmse, 1e-9 * *swing.relmse);
  EXPECT_NEAR(*swing.relmse_spatial, 0.0, 1e-12);

  auto moving = [](int t, int x, int y) { return 0.3f + 0.05f * ((t + x + y) % 5); };
  auto test = [&](int t, int x, int y) { return moving(t, x, y) * 1.2f + 0.02f * (t % 3); };
  WriteSequence(dir / "moving", Spec(9, moving));
  WriteSequence(dir / "test", Spec(9, test));
  const MetricsReport r = Measure({.test = dir / "test", .reference = dir / "moving"});
  double expected_temporal = 0, expected_spatial = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      double sw = 0, swe = 0, swe2 = 0;
      for (int t = 0; t < 9; ++t) {
        const double rv = moving(t, x, y), e = double(test(t, x, y)) - rv, w = 1 / (rv * rv + 0.01);
        sw += w, swe += w * e, swe2 += w * e * e;
      }
      expected_spatial += swe * swe / sw / (9 * 1024);
      expected_temporal += (swe2 - swe * swe / sw) / (9 * 1024);
    }
  EXPECT_NEAR(*r.relmse_spatial, expected_spatial, 1e-6 * expected_spatial);
  EXPECT_NEAR(*r.relmse_temporal, expected_temporal, 1e-6 * expected_temporal);
  EXPECT_NEAR(*r.relmse_temporal + *r.relmse_spatial, *r.relmse, 1e-12 * *r.relmse);
}

TEST(MetricsReport, WhiteNoiseHasFlatSpectrumAtItsVariance) {
  const double sigma = 0.1, fs = 60;
  const int frames = 64, length = 16;
  std::mt19937 rng(42);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(sigma));
  std::vector<float> values(static_cast<size_t>(frames) * 48 * 48);
  for (float& v : values) v = 1.0f + noise(rng);
  TempDir dir;
  WriteSequence(dir / "test", Spec(
                                  frames, [&](int t, int x, int y) { return values[(t * 48 + y) * 48 + x]; }, 48));
  MetricsReport r = Measure({.test = dir / "test", .request = {.fps = fs}, .segment_length = length});
  EXPECT_FALSE(r.tv_ref);  // reference-relative keys absent without REF
  EXPECT_EQ(r.flicker.signal, "test");
  EXPECT_NEAR(r.tv_test, sigma * sigma, 0.03 * sigma * sigma);
  const double level = 2 * sigma * sigma / fs;
  for (int k = 2; k < length / 2; ++k) EXPECT_NEAR(r.flicker.psd[k], level, 0.06 * level) << "bin " << k;
  const nlohmann::json j = ToJson(r);
  EXPECT_FALSE(j.contains("tv_ref"));
  EXPECT_FALSE(j.contains("energy_bias"));
  EXPECT_FALSE(j.contains("warp_err"));  // no motion vectors
}

// A pattern moving by (dx, dy) per frame with exact motion vectors: warping
// the previous frame along them reproduces the current one.
TEST(MetricsReport, MovingPatternWithExactMotionHasZeroWarpError) {
  auto pattern = [](double u, double v) { return 1.0 + 0.5 * std::sin(0.4 * u) * std::cos(0.3 * v); };
  for (auto [dx, dy] : {std::pair{1.0, 0.0}, std::pair{2.0, -1.0}}) {
    TempDir dir;
    SequenceSpec s = Spec(6, [&](int t, int x, int y) { return static_cast<float>(pattern(x - dx * t, y - dy * t)); });
    // The point at p in frame t was at p - (dx, dy) in frame t-1.
    s.motion = [&](int, int, int) { return cv::Vec2f(static_cast<float>(-dx), static_cast<float>(-dy)); };
    WriteSequence(dir / "test", s);
    MetricsReport r = Measure({.test = dir / "test"});
    ASSERT_TRUE(r.warp_err);
    EXPECT_LT(*r.warp_err, 1e-6) << dx << "," << dy;
    EXPECT_GT(r.temporal_diff_test, 0.05);  // without the warp the frames do differ
  }
  // Sub-pixel motion of a linear ramp: bilinear resampling is exact up to
  // OpenCV's 1/32-pixel interpolation weights.
  TempDir dir;
  SequenceSpec s = Spec(5, [](int t, int x, int) { return static_cast<float>(0.1 * (x - 0.5 * t)); });
  s.motion = [](int, int, int) { return cv::Vec2f(-0.5f, 0.0f); };
  WriteSequence(dir / "test", s);
  MetricsReport r = Measure({.test = dir / "test"});
  ASSERT_TRUE(r.warp_err);
  EXPECT_LT(*r.warp_err, 0.1 / 32);
  EXPECT_NEAR(r.temporal_diff_test, 0.05, 1e-6);
}

TEST(MetricsReport, WrongMotionGivesLargeWarpError) {
  TempDir dir;
  SequenceSpec s = Spec(4, [](int t, int x, int) { return static_cast<float>(std::sin(0.5 * (x - 2 * t))); });
  s.motion = [](int, int, int) { return cv::Vec2f(0.0f, 0.0f); };  // claims nothing moved
  WriteSequence(dir / "test", s);
  MetricsReport r = Measure({.test = dir / "test"});
  ASSERT_TRUE(r.warp_err);
  EXPECT_GT(*r.warp_err, 0.3);
}

TEST(MetricsReport, NonFinitePixelsAreExcludedAndCounted) {
  TempDir dir;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  WriteSequence(dir / "test", Spec(8, [&](int t, int x, int y) {
                  if (x == 3 && y == 4 && t == 5) return nan;
                  if (x == 7 && y == 1 && t == 0) return inf;
                  return static_cast<float>(1.0 + 0.1 * (t % 2));
                }));
  WriteSequence(dir / "ref", Spec(8, [](int, int x, int y) {
                  return x == 9 && y == 9 ? -std::numeric_limits<float>::infinity() : 1.0f;
                }));
  MetricsReport r = Measure({.test = dir / "test", .reference = dir / "ref"});
  EXPECT_EQ(r.nan_pixels, 3);
  EXPECT_EQ(r.nan_samples, 1 + 1 + 8);
  EXPECT_EQ(r.pixels, 32 * 32);
  const double variance = 0.01 / 4 * 8 / 7.0;  // alternating +-0.05 around 1.05
  EXPECT_NEAR(r.tv_test, variance, 1e-6);
  EXPECT_NEAR(*r.tv_err, variance, 1e-6);
  EXPECT_TRUE(std::isfinite(*r.energy_bias));
  EXPECT_NEAR(*r.energy_bias, 0.05, 1e-6);
  EXPECT_TRUE(std::isfinite(*r.rmse));
  for (double p : r.flicker.psd) EXPECT_TRUE(std::isfinite(p));
  EXPECT_EQ(r.region_mask.at<uint8_t>(4, 3), 0);
  bool named = false;
  for (const std::string& w : r.warnings) named = named || w.find("test/frame_0000.exr") != std::string::npos;
  EXPECT_TRUE(named) << "no warning names the first frame with a non-finite value";
}

TEST(MetricsReport, HighlightMaskRestrictsTheRegion) {
  TempDir dir;
  // Reference: one bright specular spot at (10, 10); test flickers everywhere.
  auto ref = [](int, int x, int y) { return x == 10 && y == 10 ? 5.0f : 0.2f; };
  SequenceSpec rs = Spec(4, ref);
  rs.layout = Layout::kSpecularLayer;
  WriteSequence(dir / "ref", rs);
  SequenceSpec ts = Spec(4, [](int t, int x, int y) {
    return (x < 16 ? 0.2f : 0.2f + 0.1f * (t % 2)) + (x == 10 && y == 10 ? 4.8f : 0.0f);
  });
  ts.layout = Layout::kSpecularLayer;
  WriteSequence(dir / "test", ts);
  MetricsOptions o{.test = dir / "test", .reference = dir / "ref", .highlight_mask = true};
  o.highlight.dilate_radius = 1;
  MetricsReport r = Measure(o);
  EXPECT_EQ(r.layer, "specular");
  EXPECT_EQ(r.region, "highlight");
  EXPECT_EQ(r.pixels, 5);     // OpenCV's 3x3 ellipse is a plus: the spot and its 4 neighbours
  EXPECT_EQ(r.tv_test, 0.0);  // the flicker at x >= 16 is outside
  MetricsReport whole = Measure({.test = dir / "test", .reference = dir / "ref"});
  EXPECT_GT(whole.tv_test, 0.0);

  o.highlight.threshold = 100;
  auto empty = ComputeMetrics(o);
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().find("highlight mask is empty"), std::string::npos);

  o.highlight.empty_falls_back_to_frame = true;
  MetricsReport fallback = Measure(o);
  EXPECT_EQ(fallback.region, "frame (highlight mask empty)");
  EXPECT_EQ(fallback.pixels, whole.pixels);
  EXPECT_DOUBLE_EQ(fallback.tv_test, whole.tv_test);
}

TEST(MetricsReport, MaskFileSelectsPixels) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(4, [](int t, int x, int) { return x == 0 ? 1.0f * (t % 2) : 1.0f; }));
  cv::Mat mask = cv::Mat::zeros(32, 32, CV_32F);
  mask.col(0).setTo(1.0f);
  ASSERT_TRUE(WriteExrMats(dir / "mask.exr", {{"Y", mask}}));
  MetricsReport r = Measure({.test = dir / "test", .mask_file = dir / "mask.exr"});
  EXPECT_EQ(r.pixels, 32);
  EXPECT_NEAR(r.tv_test, 0.25 * 4 / 3.0, 1e-9);
}

TEST(MetricsReportErrors, DifferentLengthsNameBothSequences) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(5, [](int, int, int) { return 1.0f; }));
  WriteSequence(dir / "ref", Spec(4, [](int, int, int) { return 1.0f; }));
  auto r = ComputeMetrics({.test = dir / "test", .reference = dir / "ref"});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("has 5 frames"), std::string::npos) << r.error();
  EXPECT_NE(r.error().find("has 4"), std::string::npos) << r.error();
}

TEST(MetricsReportErrors, DifferentSizes) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(
                                  3, [](int, int, int) { return 1.0f; }, 16));
  WriteSequence(dir / "ref", Spec(
                                 3, [](int, int, int) { return 1.0f; }, 32));
  auto r = ComputeMetrics({.test = dir / "test", .reference = dir / "ref"});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("16x16"), std::string::npos) << r.error();
}

TEST(MetricsReportErrors, BadOptions) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(4, [](int, int, int) { return 1.0f; }));
  auto r = ComputeMetrics({.test = dir / "test", .signal = FlickerSignal::kError});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("needs a reference"), std::string::npos);
  r = ComputeMetrics({.test = dir / "test", .segment_length = 5});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("--segment 5"), std::string::npos);
  WriteSequence(dir / "one", Spec(1, [](int, int, int) { return 1.0f; }));
  r = ComputeMetrics({.test = dir / "one"});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("at least 2"), std::string::npos);
}

TEST(MetricsReportErrors, TruncatedFrameStopsThePass) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(
                                  4, [](int t, int x, int) { return 0.1f * (t + x); }, 64));
  const auto file = dir / "test" / "frame_0002.exr";
  std::filesystem::resize_file(file, std::filesystem::file_size(file) / 2);
  auto r = ComputeMetrics({.test = dir / "test"});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("frame_0002.exr"), std::string::npos) << r.error();
}

}  // namespace
}  // namespace shimmer::metrics

#include "shimmer/metrics/metrics_accumulator.h"

namespace shimmer::metrics {
namespace {

// Frames fed from memory give exactly what the EXR pass gives on the same
// frames: the accumulator is the pass, ComputeMetrics only reads files into it.
TEST(MetricsAccumulator, FramesFromMemoryMatchTheExrPass) {
  testing::TempDir dir;
  auto test_value = [](int t, int x, int y) { return 0.5f + 0.25f * std::sin(0.9f * t + 0.3f * x) + 0.01f * y; };
  auto ref_value = [](int, int x, int y) { return 0.5f + 0.01f * (x + y); };
  testing::WriteSequence(dir / "test", Spec(12, test_value));
  testing::WriteSequence(dir / "ref", Spec(12, ref_value));
  const MetricsReport from_files = Measure({.test = dir / "test", .reference = dir / "ref", .request = {.fps = 30.0}});

  AccumulatorSetup setup;
  setup.width = setup.height = 32;
  setup.frames = 12;
  setup.fps = 30;
  setup.has_reference = true;
  setup.region = cv::Mat::ones(32, 32, CV_8U);
  setup.signal = FlickerSignal::kError;
  setup.segment_length = 12;
  MetricsAccumulator accumulator(setup);
  cv::Mat T(32, 32, CV_32F), R(32, 32, CV_32F);
  for (int t = 0; t < 12; ++t) {
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 32; ++x) T.at<float>(y, x) = test_value(t, x, y), R.at<float>(y, x) = ref_value(t, x, y);
    accumulator.AddFrame(T, R, cv::Mat(), "t", "r");  // the same planes, refilled: the accumulator keeps copies
  }
  MetricsReport from_memory;
  ASSERT_TRUE(accumulator.Finish(&from_memory));
  EXPECT_EQ(from_memory.tv_test, from_files.tv_test);
  EXPECT_EQ(*from_memory.tv_err, *from_files.tv_err);
  EXPECT_EQ(*from_memory.energy_bias, *from_files.energy_bias);
  EXPECT_EQ(*from_memory.temporal_diff_err, *from_files.temporal_diff_err);
  EXPECT_EQ(*from_memory.relmse, *from_files.relmse);
  EXPECT_EQ(from_memory.flicker.psd, from_files.flicker.psd);
  EXPECT_EQ(from_memory.flicker.flicker_index, from_files.flicker.flicker_index);
  EXPECT_GT(*from_memory.tv_err, 0.0);
}

}  // namespace
}  // namespace shimmer::metrics
