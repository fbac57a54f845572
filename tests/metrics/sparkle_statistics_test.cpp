// Known-answer tests of the sparkle statistics (docs/metrics.md, "Sparkle
// statistics") through the whole pass, on small sequences generated here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

#include "shimmer/metrics/metrics_report.h"
#include "shimmer/metrics/sparkle_statistics.h"
#include "test_sequences.h"

namespace shimmer::metrics {
namespace {

using testing::Layout;
using testing::SequenceSpec;
using testing::TempDir;
using testing::WriteExrMats;
using testing::WriteSequence;

constexpr float kDark = 0.1f, kBright = 5.0f;
// A sparkle stands out of its neighbourhood by more than this (kBright / kDark is 50).
constexpr double kTau = 4.0;

SequenceSpec Spec(int frames, testing::PixelFunction f) {
  SequenceSpec s;
  s.frames = frames;
  s.width = s.height = 16;
  s.layout = Layout::kLuminanceY;
  s.value = std::move(f);
  return s;
}

// Everything moves by (dx, dy) pixels per frame: the point at p in frame t was at p - (dx, dy) in frame t-1.
std::function<cv::Vec2f(int, int, int)> Motion(float dx, float dy) {
  return [=](int, int, int) { return cv::Vec2f(-dx, -dy); };
}

MetricsReport Measure(const MetricsOptions& options) {
  auto report = ComputeMetrics(options);
  EXPECT_TRUE(report) << report.error();
  return report ? *report : MetricsReport{};
}

const SparkleStatistics& TestSide(const MetricsReport& r) {
  static const SparkleStatistics none;
  EXPECT_TRUE(r.sparkles);
  return r.sparkles ? r.sparkles->test : none;
}

bool HasWarning(const MetricsReport& r, const std::string& part) {
  for (const std::string& w : r.warnings)
    if (w.find(part) != std::string::npos) return true;
  return false;
}

// count_t pixels of row 2 are bright in frame t; one more pixel, brighter
// than its neighbourhood by less than the contrast, never counts.
TEST(SparkleStatistics, CountPatternGivesExactMeanAndPopulationVariance) {
  const std::vector<long long> pattern = {1, 3, 0, 2, 4, 2};
  TempDir dir;
  WriteSequence(dir / "test", Spec(6, [&](int t, int x, int y) {
                  if (x == 15 && y == 15) return static_cast<float>(0.9 * kTau * kDark);
                  return y == 2 && x < pattern[t] ? kBright : kDark;
                }));
  MetricsReport r = Measure({.test = dir / "test", .sparkle_threshold = kTau});
  const SparkleStatistics& s = TestSide(r);
  EXPECT_EQ(r.sparkles->threshold, kTau);
  EXPECT_EQ(s.counts, pattern);
  EXPECT_DOUBLE_EQ(s.mean_count, 2.0);
  // (1 + 1 + 4 + 0 + 4 + 0) / 6: the population variance, not the sample one (/5).
  EXPECT_DOUBLE_EQ(s.count_variance, 10.0 / 6.0);
  ASSERT_TRUE(s.count_cv);
  EXPECT_DOUBLE_EQ(*s.count_cv, std::sqrt(10.0 / 6.0) / 2.0);
  EXPECT_FALSE(r.sparkles->reference);
  EXPECT_FALSE(r.sparkles->mean_count_ratio);
}

// A dot born in frame 2 that moves one pixel a frame and is gone after frame
// 6, with exact motion vectors: one birth, one track of L = 5 frames.
TEST(SparkleStatistics, MovingDotWithMotionLivesItsWholeTrack) {
  const int first = 2, last = 6, length = last - first + 1;
  for (auto [dx, dy] : {std::pair{1, 0}, std::pair{1, 1}, std::pair{0, -1}}) {
    TempDir dir;
    SequenceSpec s = Spec(10, [&](int t, int x, int y) {
      return t >= first && t <= last && x == 4 + dx * t && y == 8 + dy * t ? kBright : kDark;
    });
    s.motion = Motion(static_cast<float>(dx), static_cast<float>(dy));
    WriteSequence(dir / "test", s);
    MetricsReport r = Measure({.test = dir / "test", .sparkle_threshold = kTau});
    const SparkleStatistics& st = TestSide(r);
    EXPECT_EQ(st.births, 1) << dx << "," << dy;
    ASSERT_TRUE(st.mean_lifetime);
    EXPECT_EQ(*st.mean_lifetime, length) << dx << "," << dy;
    ASSERT_TRUE(st.birth_rate);
    EXPECT_DOUBLE_EQ(*st.birth_rate, 1.0 / length);
    EXPECT_EQ(st.motion, "test");
    EXPECT_FALSE(HasWarning(r, "sparkle"));
  }
}

// Half a pixel a frame: the dot steps every other frame, and the warped
// position falls between two pixel centres, both of which are looked at.
TEST(SparkleStatistics, SubPixelMotionLooksAtTheBilinearFootprint) {
  TempDir dir;
  SequenceSpec s =
      Spec(9, [](int t, int x, int y) { return t >= 1 && y == 7 && x == 3 + t / 2 ? kBright : kDark; });
  s.motion = Motion(0.5f, 0.0f);
  WriteSequence(dir / "test", s);
  MetricsReport r = Measure({.test = dir / "test", .sparkle_threshold = kTau});
  ASSERT_TRUE(TestSide(r).mean_lifetime);
  EXPECT_EQ(*TestSide(r).mean_lifetime, 8.0);
  EXPECT_EQ(TestSide(r).births, 1);
}

// Motion vectors of the wrong sign point at where the dot will be, which was
// dark: every frame is a new birth. (Holds the sign convention of warp_err.)
TEST(SparkleStatistics, MotionOfTheWrongSignFindsNoPredecessor) {
  TempDir dir;
  SequenceSpec s = Spec(8, [](int t, int x, int y) { return t >= 1 && y == 5 && x == 2 + t ? kBright : kDark; });
  s.motion = Motion(-1.0f, 0.0f);
  WriteSequence(dir / "test", s);
  MetricsReport r = Measure({.test = dir / "test", .sparkle_threshold = kTau});
  EXPECT_EQ(TestSide(r).births, 7);
  EXPECT_EQ(*TestSide(r).mean_lifetime, 1.0);
}

// The same moving dot in a sequence without motion channels: tracked in
// place, it is a new sparkle in each frame, and a warning says so.
TEST(SparkleStatistics, MovingDotWithoutMotionIsBornEveryFrame) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(10, [](int t, int x, int y) {
                  return t >= 2 && t <= 6 && x == 4 + t && y == 8 ? kBright : kDark;
                }));
  MetricsReport r = Measure({.test = dir / "test", .sparkle_threshold = kTau});
  const SparkleStatistics& s = TestSide(r);
  EXPECT_EQ(s.births, 5);
  ASSERT_TRUE(s.mean_lifetime);
  EXPECT_EQ(*s.mean_lifetime, 1.0);
  EXPECT_EQ(*s.birth_rate, 1.0);
  EXPECT_EQ(s.motion, "none");
  EXPECT_TRUE(HasWarning(r, "sparkle lifetimes tracked without motion vectors (TEST has no motion.X/Y)"));
}

// A still dot that is bright every other frame: each bright frame a birth.
// Beside it a still dot that comes on in frame 3 and stays: one birth, its
// track cut at the last frame (N - 3 frames).
TEST(SparkleStatistics, BlinkingDotLivesOneFrame) {
  const int frames = 9;
  TempDir dir;
  SequenceSpec s = Spec(frames, [](int t, int x, int y) {
    if (x == 3 && y == 3) return t % 2 == 1 ? kBright : kDark;
    return x == 10 && y == 10 && t >= 3 ? kBright : kDark;
  });
  s.motion = Motion(0, 0);
  WriteSequence(dir / "test", s);
  MetricsReport r = Measure({.test = dir / "test", .sparkle_threshold = kTau});
  const SparkleStatistics& st = TestSide(r);
  EXPECT_EQ(st.births, 4 + 1);
  EXPECT_EQ(st.tracked, 4 + (frames - 3));
  EXPECT_DOUBLE_EQ(*st.mean_lifetime, (4.0 + (frames - 3)) / 5.0);

  TempDir blink;
  SequenceSpec only = Spec(frames, [](int t, int x, int y) { return x == 3 && y == 3 && t % 2 == 1 ? kBright : kDark; });
  only.motion = Motion(0, 0);
  WriteSequence(blink / "test", only);
  MetricsReport b = Measure({.test = blink / "test", .sparkle_threshold = kTau});
  EXPECT_EQ(*TestSide(b).mean_lifetime, 1.0);
  EXPECT_EQ(*TestSide(b).birth_rate, 1.0);
}

// Frame 0's sparkles were born before the sequence: they, and the tracks that
// continue them, are left out of the lifetime (and are not births).
TEST(SparkleStatistics, TracksFromFrameZeroAreLeftOutOfTheLifetime) {
  TempDir dir;
  SequenceSpec s = Spec(8, [](int t, int x, int y) { return x == 1 + t && y == 4 ? kBright : kDark; });
  s.motion = Motion(1, 0);
  WriteSequence(dir / "test", s);
  MetricsReport r = Measure({.test = dir / "test", .sparkle_threshold = kTau});
  const SparkleStatistics& st = TestSide(r);
  EXPECT_EQ(st.births, 0);
  EXPECT_EQ(st.tracked, 0);
  EXPECT_FALSE(st.mean_lifetime);  // no birth seen: undefined
  ASSERT_TRUE(st.birth_rate);
  EXPECT_EQ(*st.birth_rate, 0.0);  // 7 sparkle pixel-frames after frame 0, none of them new
  EXPECT_DOUBLE_EQ(st.mean_count, 1.0);
  EXPECT_EQ(st.count_variance, 0.0);
  EXPECT_EQ(*st.count_cv, 0.0);
}

// Test: a dot blinking on odd frames and a moving dot present from frame 0.
// Reference: two moving dots from frame 1 on, in frames without motion
// channels, tracked through the test's motion vectors.
TEST(SparkleStatistics, ReferenceAndRatios) {
  TempDir dir;
  SequenceSpec test = Spec(8, [](int t, int x, int y) {
    if (x == 3 && y == 3) return t % 2 == 1 ? kBright : kDark;
    return x == 1 + t && y == 10 ? kBright : kDark;
  });
  test.motion = Motion(1, 0);
  WriteSequence(dir / "test", test);
  WriteSequence(dir / "ref", Spec(8, [](int t, int x, int y) {
                  return t >= 1 && x == 2 + t && (y == 12 || y == 14) ? kBright : kDark;
                }));
  MetricsReport r = Measure({.test = dir / "test", .reference = dir / "ref", .sparkle_threshold = kTau});
  ASSERT_TRUE(r.sparkles && r.sparkles->reference);
  const SparkleStatistics &t = r.sparkles->test, &ref = *r.sparkles->reference;
  EXPECT_EQ(t.counts, (std::vector<long long>{1, 2, 1, 2, 1, 2, 1, 2}));
  EXPECT_DOUBLE_EQ(t.mean_count, 1.5);
  EXPECT_DOUBLE_EQ(t.count_variance, 0.25);
  EXPECT_EQ(*t.mean_lifetime, 1.0);
  EXPECT_DOUBLE_EQ(*t.birth_rate, 4.0 / 11.0);
  EXPECT_EQ(ref.counts, (std::vector<long long>{0, 2, 2, 2, 2, 2, 2, 2}));
  EXPECT_DOUBLE_EQ(ref.mean_count, 1.75);
  EXPECT_DOUBLE_EQ(ref.count_variance, 0.4375);
  EXPECT_EQ(*ref.mean_lifetime, 7.0);
  EXPECT_DOUBLE_EQ(*ref.birth_rate, 2.0 / 14.0);
  EXPECT_EQ(ref.motion, "test");
  EXPECT_DOUBLE_EQ(*r.sparkles->mean_count_ratio, 1.5 / 1.75);
  EXPECT_DOUBLE_EQ(*r.sparkles->count_variance_ratio, 0.25 / 0.4375);
  EXPECT_DOUBLE_EQ(*r.sparkles->lifetime_ratio, 1.0 / 7.0);
  EXPECT_FALSE(HasWarning(r, "sparkle"));

  const nlohmann::json j = ToJson(r)["sparkles"];
  EXPECT_EQ(j["threshold"], kTau);
  for (const char* side : {"test", "reference"})
    for (const char* key : {"mean_count", "count_variance", "count_cv", "mean_lifetime", "birth_rate", "motion"})
      EXPECT_TRUE(j[side].contains(key)) << side << " " << key;
  EXPECT_EQ(j["reference"]["mean_lifetime"], 7.0);
  EXPECT_EQ(j["lifetime_ratio"], 1.0 / 7.0);
  EXPECT_EQ(j["mean_count_ratio"], 1.5 / 1.75);
  EXPECT_EQ(j["count_variance_ratio"], 0.25 / 0.4375);
}

// A reference with its own motion channels follows them, not the test's.
// Sparkles as independent draws: pixel (x, y) of frame t is bright with
// probability p (a hash of x, y, t and the seed), on a 48 x 48 frame of 24
// frames. Two sequences of one p are two realisations of one law.
SequenceSpec RandomSparkles(double p, unsigned seed) {
  SequenceSpec s = Spec(24, [p, seed](int t, int x, int y) {
    std::uint64_t h = (static_cast<std::uint64_t>(seed) << 40) ^ (static_cast<std::uint64_t>(t) << 24) ^
                      (static_cast<std::uint64_t>(y) << 12) ^ static_cast<std::uint64_t>(x);
    h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
    h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
    h ^= h >> 31;
    return static_cast<double>(h >> 11) * 0x1.0p-53 < p ? kBright : kDark;
  });
  s.width = s.height = 48;
  s.motion = Motion(0, 0);
  return s;
}

// The ratios' intervals: a test that is its reference has every ratio 1
// in every resample, so the intervals are the point; two realisations of
// one law have intervals that hold 1 (in 19 of 20 pairs or more: 95 %
// intervals, with slack for 20 draws); twice the density has a count
// ratio whose interval holds 2 and not 1.
TEST(SparkleStatistics, RatioIntervalsHoldWhatTheSequencesShare) {
  TempDir same;
  WriteSequence(same / "test", RandomSparkles(0.02, 1));
  MetricsReport r = Measure({.test = same / "test", .reference = same / "test", .sparkle_threshold = kTau});
  ASSERT_TRUE(r.sparkles && r.sparkles->mean_count_ratio_ci && r.sparkles->lifetime_ratio_ci);
  EXPECT_DOUBLE_EQ(r.sparkles->mean_count_ratio_ci->lo, 1.0);
  EXPECT_DOUBLE_EQ(r.sparkles->mean_count_ratio_ci->hi, 1.0);
  EXPECT_DOUBLE_EQ(r.sparkles->lifetime_ratio_ci->lo, 1.0);
  EXPECT_DOUBLE_EQ(r.sparkles->lifetime_ratio_ci->hi, 1.0);

  int count_holds = 0, variance_holds = 0, lifetime_holds = 0;
  for (unsigned pair = 0; pair < 20; ++pair) {
    TempDir dir;
    WriteSequence(dir / "test", RandomSparkles(0.02, 100 + 2 * pair));
    WriteSequence(dir / "reference", RandomSparkles(0.02, 101 + 2 * pair));
    MetricsReport m = Measure({.test = dir / "test", .reference = dir / "reference", .sparkle_threshold = kTau});
    ASSERT_TRUE(m.sparkles && m.sparkles->mean_count_ratio_ci && m.sparkles->count_variance_ratio_ci &&
                m.sparkles->lifetime_ratio_ci);
    const SparkleReport& sp = *m.sparkles;
    auto holds = [](const Interval& i, double v) { return i.lo <= v && v <= i.hi; };
    EXPECT_LT(sp.mean_count_ratio_ci->lo, *sp.mean_count_ratio);
    EXPECT_GT(sp.mean_count_ratio_ci->hi, *sp.mean_count_ratio);
    EXPECT_GE(sp.count_variance_ratio_ci->lo, 0.0);  // a ratio of variances, never below 0
    count_holds += holds(*sp.mean_count_ratio_ci, 1.0);
    variance_holds += holds(*sp.count_variance_ratio_ci, 1.0);
    lifetime_holds += holds(*sp.lifetime_ratio_ci, 1.0);
  }
  std::printf("1 inside the intervals of 20 pairs of one law: count %d, count variance %d, lifetime %d\n",
              count_holds, variance_holds, lifetime_holds);
  EXPECT_GE(count_holds, 17);
  EXPECT_GE(variance_holds, 17);
  EXPECT_GE(lifetime_holds, 17);

  TempDir twice;
  WriteSequence(twice / "test", RandomSparkles(0.04, 7));
  WriteSequence(twice / "reference", RandomSparkles(0.02, 8));
  MetricsReport d = Measure({.test = twice / "test", .reference = twice / "reference", .sparkle_threshold = kTau});
  ASSERT_TRUE(d.sparkles && d.sparkles->mean_count_ratio_ci);
  EXPECT_GT(d.sparkles->mean_count_ratio_ci->lo, 1.5);
  EXPECT_LT(d.sparkles->mean_count_ratio_ci->lo, 2.0);
  EXPECT_GT(d.sparkles->mean_count_ratio_ci->hi, 2.0);
}

TEST(SparkleStatistics, ReferenceFollowsItsOwnMotionWhenItHasSome) {
  TempDir dir;
  SequenceSpec test = Spec(6, [](int, int, int) { return kDark; });
  test.motion = Motion(0, 0);  // wrong for the reference's moving dot
  WriteSequence(dir / "test", test);
  SequenceSpec ref = Spec(6, [](int t, int x, int y) { return t >= 1 && x == 2 + t && y == 6 ? kBright : kDark; });
  ref.motion = Motion(1, 0);
  WriteSequence(dir / "ref", ref);
  MetricsReport r = Measure({.test = dir / "test", .reference = dir / "ref", .sparkle_threshold = kTau});
  ASSERT_TRUE(r.sparkles && r.sparkles->reference);
  EXPECT_EQ(r.sparkles->reference->motion, "reference");
  EXPECT_EQ(*r.sparkles->reference->mean_lifetime, 5.0);
  // The test has no sparkle: its mean count is 0 and every ratio with it in a denominator is undefined.
  EXPECT_EQ(r.sparkles->test.mean_count, 0.0);
  EXPECT_FALSE(r.sparkles->test.count_cv);
  EXPECT_FALSE(r.sparkles->test.mean_lifetime);
  EXPECT_FALSE(r.sparkles->test.birth_rate);
  EXPECT_EQ(*r.sparkles->mean_count_ratio, 0.0);
  EXPECT_FALSE(r.sparkles->lifetime_ratio);
  EXPECT_TRUE(ToJson(r)["sparkles"]["lifetime_ratio"].is_null());
}

// Only the region counts, and a non-finite sample is never a sparkle.
TEST(SparkleStatistics, OnlyFiniteSamplesInTheRegionCount) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(4, [](int t, int x, int y) {
                  if (x == 2 && y == 2) return kBright;                                             // in, always
                  if (x == 12 && y == 12) return kBright;                                           // outside the mask
                  if (x == 3 && y == 2) return t == 1 ? std::numeric_limits<float>::infinity() : kDark;  // in
                  return kDark;
                }));
  cv::Mat mask = cv::Mat::zeros(16, 16, CV_32F);
  mask(cv::Rect(0, 0, 8, 8)) = 1.0f;
  ASSERT_TRUE(WriteExrMats(dir / "mask.exr", {{"Y", mask}}));
  MetricsReport r = Measure({.test = dir / "test", .mask_file = dir / "mask.exr", .sparkle_threshold = kTau});
  EXPECT_EQ(TestSide(r).counts, (std::vector<long long>{1, 1, 1, 1}));
  EXPECT_EQ(r.nan_samples, 1);
}

// Off (the default): no sparkles in the report or its JSON, and turning them
// on changes nothing else in the JSON.
TEST(SparkleStatistics, OffLeavesTheReportAsItWas) {
  TempDir dir;
  SequenceSpec s = Spec(6, [](int t, int x, int y) { return (x + y + t) % 5 == 0 ? kBright : kDark; });
  s.motion = Motion(1, 0);
  WriteSequence(dir / "test", s);
  WriteSequence(dir / "ref", Spec(6, [](int, int x, int y) { return (x * y) % 7 == 0 ? kBright : kDark; }));
  MetricsReport off = Measure({.test = dir / "test", .reference = dir / "ref"});
  EXPECT_FALSE(off.sparkles);
  const nlohmann::json j_off = ToJson(off);
  EXPECT_FALSE(j_off.contains("sparkles"));
  MetricsReport on = Measure({.test = dir / "test", .reference = dir / "ref", .sparkle_threshold = kTau});
  nlohmann::json j_on = ToJson(on);
  ASSERT_TRUE(j_on.contains("sparkles"));
  EXPECT_GT(j_on["sparkles"]["test"]["mean_count"].get<double>(), 0.0);
  j_on.erase("sparkles");
  EXPECT_EQ(j_on.dump(), j_off.dump());
  // Without a reference: no reference and no ratios.
  const nlohmann::json alone = ToJson(Measure({.test = dir / "test", .sparkle_threshold = kTau}))["sparkles"];
  EXPECT_TRUE(alone.contains("test"));
  for (const char* key : {"reference", "mean_count_ratio", "count_variance_ratio", "lifetime_ratio"})
    EXPECT_FALSE(alone.contains(key)) << key;
}

// The count is a contrast: the same frames at any exposure give the same
// sparkles, and so do frames whose shading is scaled across the picture.
TEST(SparkleStatistics, ScalingTheLuminanceLeavesTheCountsAsTheyAre) {
  auto field = [](double scale, double slope) {
    return [=](int t, int x, int y) {
      const double shading = scale * (1 + slope * x);  // a smooth level, as D_g's
      const bool glint = (x * 7 + y * 13 + t * 5) % 11 == 0;
      return static_cast<float>(shading * (glint ? 10.0 : 1.0));
    };
  };
  TempDir dir;
  WriteSequence(dir / "base", Spec(5, field(1.0, 0.0)));
  const std::vector<long long> counts = TestSide(Measure({.test = dir / "base", .sparkle_threshold = kTau})).counts;
  ASSERT_EQ(counts.size(), 5u);
  EXPECT_GT(counts[0], 10);
  for (double scale : {1e-3, 1e3}) {
    TempDir scaled;
    WriteSequence(scaled / "test", Spec(5, field(scale, 0.0)));
    EXPECT_EQ(TestSide(Measure({.test = scaled / "test", .sparkle_threshold = kTau})).counts, counts) << scale;
  }
  // A shading ramp of 4 % per pixel moves no pixel across the contrast of 4
  // against a glint of 10 times its level.
  TempDir ramp;
  WriteSequence(ramp / "test", Spec(5, field(1.0, 0.04)));
  EXPECT_EQ(TestSide(Measure({.test = ramp / "test", .sparkle_threshold = kTau})).counts, counts);
}

// Smooth shading has no sparkle at any level; a glint on it does.
TEST(SparkleStatistics, SmoothShadingHasNoSparklesButAGlintOnItDoes) {
  auto highlight = [](int x, int y) {
    const double dx = x - 7.5, dy = y - 7.5;
    return 0.05 + 20.0 * std::exp(-(dx * dx + dy * dy) / 18.0);  // 400 times its surround, as wide as a neighbourhood
  };
  TempDir dir;
  WriteSequence(dir / "smooth", Spec(3, [&](int, int x, int y) { return static_cast<float>(highlight(x, y)); }));
  EXPECT_EQ(TestSide(Measure({.test = dir / "smooth", .sparkle_threshold = kTau})).counts,
            (std::vector<long long>{0, 0, 0}));
  WriteSequence(dir / "glint", Spec(3, [&](int, int x, int y) {
                  return static_cast<float>(highlight(x, y) * (x == 2 && y == 3 ? 30.0 : 1.0));
                }));
  EXPECT_EQ(TestSide(Measure({.test = dir / "glint", .sparkle_threshold = kTau})).counts,
            (std::vector<long long>{1, 1, 1}));
}

// The region's edge is not a contrast: pixels outside it do not darken a
// neighbourhood. A bright square region on black shows no sparkle.
TEST(SparkleStatistics, TheRegionsEdgeIsNoSparkle) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(2, [](int, int x, int y) {
                  return x >= 4 && x < 12 && y >= 4 && y < 12 ? kBright : 0.0f;
                }));
  cv::Mat mask = cv::Mat::zeros(16, 16, CV_32F);
  mask(cv::Rect(4, 4, 8, 8)) = 1.0f;
  ASSERT_TRUE(WriteExrMats(dir / "mask.exr", {{"Y", mask}}));
  EXPECT_EQ(TestSide(Measure({.test = dir / "test", .mask_file = dir / "mask.exr", .sparkle_threshold = kTau}))
                .counts,
            (std::vector<long long>{0, 0}));
}

// On a black background a speck's neighbourhood mean is 0: the floor (a
// share of the frame's mean) decides. A third of a 48-pixel-wide frame at
// 1, the rest black: the floor is 0.05 / 3, so a speck must be above 4 times
// that, 0.0667.
TEST(SparkleStatistics, ASpeckOnBlackMustClearTheFloor) {
  for (auto [speck, counted] : {std::pair{0.05f, 0LL}, std::pair{0.1f, 1LL}}) {
    TempDir dir;
    SequenceSpec s = Spec(2, [speck = speck](int, int x, int y) {
      if (x < 16) return 1.0f;
      return x == 40 && y == 8 ? speck : 0.0f;
    });
    s.width = 48;
    WriteSequence(dir / "test", s);
    const auto counts = TestSide(Measure({.test = dir / "test", .sparkle_threshold = kTau})).counts;
    EXPECT_EQ(counts, (std::vector<long long>{counted, counted})) << speck;
  }
  EXPECT_NEAR(kSparkleFloorShare, 0.05, 1e-12);  // the figure the comment above uses
}

TEST(SparkleStatistics, NegativeOrNonFiniteThresholdIsRefused) {
  TempDir dir;
  WriteSequence(dir / "test", Spec(3, [](int, int, int) { return kDark; }));
  for (double tau : {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    auto r = ComputeMetrics({.test = dir / "test", .sparkle_threshold = tau});
    ASSERT_FALSE(r) << tau;
    EXPECT_NE(r.error().find("sparkle_threshold must be a finite number >= 0"), std::string::npos) << r.error();
  }
}

}  // namespace
}  // namespace shimmer::metrics
