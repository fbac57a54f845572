// The 95 % intervals and tv_err_floor: coverage on synthetic errors of known
// variance, determinism, and the reference noise read from stderr.Y.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include <opencv2/core.hpp>

#include "shimmer/metrics/metrics_accumulator.h"
#include "shimmer/metrics/metrics_report.h"
#include "test_sequences.h"

namespace shimmer::metrics {
namespace {

constexpr int kSize = 32, kFrames = 24;

// A static reference pattern R(x, y) and a test (1 + beta) R + sigma n_t,
// n a per-pixel stationary unit-variance process: white, or AR(1) with
// coefficient phi. True energy_bias = beta; the expected tv_err is sigma^2
// times the expected sample variance of a unit process of kFrames samples.
struct Synthetic {
  double sigma = 0.1, beta = 0.02, phi = 0;
  std::uint64_t seed = 1;
};

double ReferenceAt(int x, int y) { return 1.0 + 0.5 * std::sin(0.4 * x) * std::cos(0.3 * y); }

// E[s^2] / sigma^2 for a stationary series with autocorrelation phi^k:
// 1 - 2/(n(n-1)) sum_{k=1}^{n-1} (n-k) phi^k.
double ExpectedSampleVarianceFactor(double phi, int n) {
  double sum = 0;
  for (int k = 1; k < n; ++k) sum += (n - k) * std::pow(phi, k);
  return 1.0 - 2.0 * sum / (double(n) * (n - 1));
}

AccumulatorSetup Setup(bool stderr_y = false) {
  AccumulatorSetup setup;
  setup.width = setup.height = kSize;
  setup.frames = kFrames;
  setup.fps = 30;
  setup.has_reference = true;
  setup.region = cv::Mat::ones(kSize, kSize, CV_8U);
  setup.signal = FlickerSignal::kError;
  setup.segment_length = kFrames;
  setup.reference_stderr = stderr_y;
  return setup;
}

MetricsReport Simulate(const Synthetic& s) {
  MetricsAccumulator accumulator(Setup());
  std::mt19937_64 random(s.seed);
  std::normal_distribution<double> normal;
  std::vector<double> noise(kSize * kSize);
  const double innovation = std::sqrt(1 - s.phi * s.phi);
  cv::Mat T(kSize, kSize, CV_32F), R(kSize, kSize, CV_32F);
  for (int t = 0; t < kFrames; ++t) {
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        double& n = noise[y * kSize + x];
        n = t == 0 ? normal(random) : s.phi * n + innovation * normal(random);
        R.at<float>(y, x) = static_cast<float>(ReferenceAt(x, y));
        T.at<float>(y, x) = static_cast<float>((1 + s.beta) * ReferenceAt(x, y) + s.sigma * n);
      }
    accumulator.AddFrame(T, R, cv::Mat(), "t", "r");
  }
  MetricsReport report;
  EXPECT_TRUE(accumulator.Finish(&report));
  return report;
}

struct Coverage {
  int tv_err = 0, energy_bias = 0;
};

Coverage CountCoverage(Synthetic s, int trials) {
  const double true_tv_err = s.sigma * s.sigma * ExpectedSampleVarianceFactor(s.phi, kFrames);
  Coverage covered;
  for (int trial = 0; trial < trials; ++trial) {
    s.seed = 1000 + trial;
    const MetricsReport r = Simulate(s);
    const Interval tv = *r.ci95->tv_err, bias = *r.ci95->energy_bias;
    covered.tv_err += tv.lo <= true_tv_err && true_tv_err <= tv.hi;
    covered.energy_bias += bias.lo <= s.beta && s.beta <= bias.hi;
  }
  return covered;
}

// A 95 % interval covers the true value in 90-99 % of 200 seeded trials.
void ExpectNominalCoverage(const Coverage& c, const char* noise) {
  std::printf("%s: tv_err covered %d/200, energy_bias %d/200\n", noise, c.tv_err, c.energy_bias);
  EXPECT_GE(c.tv_err, 180) << noise;
  EXPECT_LE(c.tv_err, 198) << noise;
  EXPECT_GE(c.energy_bias, 180) << noise;
  EXPECT_LE(c.energy_bias, 198) << noise;
}

TEST(MetricsIntervals, CoverTheTrueValueOfWhiteNoiseIn90To99PercentOfTrials) {
  ExpectNominalCoverage(CountCoverage({.phi = 0}, 200), "white noise");
}

TEST(MetricsIntervals, CoverTheTrueValueOfAr1NoiseIn90To99PercentOfTrials) {
  ExpectNominalCoverage(CountCoverage({.phi = 0.5}, 200), "AR(1), phi 0.5");
}

TEST(MetricsIntervals, RerunsGiveIdenticalIntervalsThatHoldTheValue) {
  const MetricsReport a = Simulate({.phi = 0.3, .seed = 7}), b = Simulate({.phi = 0.3, .seed = 7});
  ASSERT_TRUE(a.ci95 && b.ci95);
  auto same = [](const std::optional<Interval>& x, const std::optional<Interval>& y) {
    ASSERT_TRUE(x && y);
    EXPECT_EQ(x->lo, y->lo);
    EXPECT_EQ(x->hi, y->hi);
  };
  same(a.ci95->tv_err, b.ci95->tv_err);
  same(a.ci95->energy_bias, b.ci95->energy_bias);
  same(a.ci95->relmse, b.ci95->relmse);
  same(a.ci95->flicker_index, b.ci95->flicker_index);
  auto holds = [](const std::optional<Interval>& i, double v) {
    ASSERT_TRUE(i);
    EXPECT_LE(i->lo, v);
    EXPECT_LE(v, i->hi);
    EXPECT_LT(i->lo, i->hi);
  };
  holds(a.ci95->tv_err, *a.tv_err);
  holds(a.ci95->energy_bias, *a.energy_bias);
  holds(a.ci95->relmse, *a.relmse);
  holds(a.ci95->flicker_index, a.flicker.flicker_index);
  EXPECT_FALSE(a.ci95->tv_ratio);  // a static reference: tv_ref = 0, no ratio
  EXPECT_FALSE(a.tv_err_floor);    // no stderr.Y
  ASSERT_TRUE(a.bootstrap);
  EXPECT_EQ(a.bootstrap->frame_block, 3);  // round(cbrt(24))
  EXPECT_EQ(a.bootstrap->tile, 8);
  EXPECT_EQ(a.bootstrap->replicates, 1000);
}

TEST(MetricsIntervals, FrameBlocksAreAboutTheCubeRootOfTheFrameCountAndAtLeastTwo) {
  EXPECT_EQ(FrameBlockLength(2), 2);
  EXPECT_EQ(FrameBlockLength(8), 2);
  EXPECT_EQ(FrameBlockLength(24), 3);
  EXPECT_EQ(FrameBlockLength(48), 4);
  EXPECT_EQ(FrameBlockLength(64), 4);
  EXPECT_EQ(FrameBlockLength(1000), 10);
}

// With every tile and block once, the sufficient statistics give back the
// metrics the pass computed: the bootstrap resamples the same estimators.
TEST(MetricsIntervals, SufficientStatisticsReproduceThePassMetrics) {
  const std::vector<int> blocks = {3, 3, 2};
  TileBlockStatistics cells(blocks);
  // Two tiles of one pixel each: T = 1 + t, R = 0.5 (one) and T = 2 - t / 8, R = 1 + t / 16 (other).
  std::mt19937 random(3);
  std::uniform_real_distribution<float> u(0.2f, 2.f);
  std::vector<std::vector<double>> test(2), ref(2);
  for (int p = 0; p < 2; ++p)
    for (int t = 0; t < 8; ++t) test[p].push_back(u(random)), ref[p].push_back(u(random));
  double sum_t = 0, sum_r = 0, tv_err = 0, tv_test = 0, rel = 0, rel_temporal = 0;
  for (int p = 0; p < 2; ++p) {
    using S = TileBlockStatistics;
    std::vector<float> sums(S::kCellSums * 3, 0.f);
    auto at = [&](S::CellSum kind, int k) -> float& { return sums[kind * 3 + k]; };
    double mt = 0, me = 0, sw = 0, swe = 0;
    for (int t = 0; t < 8; ++t) mt += test[p][t] / 8, me += (test[p][t] - ref[p][t]) / 8;
    for (int t = 0; t < 8; ++t) {
      const double w = 1 / (ref[p][t] * ref[p][t] + 0.01);
      sw += w, swe += w * (test[p][t] - ref[p][t]);
    }
    for (int t = 0; t < 8; ++t) {
      const double w = 1 / (ref[p][t] * ref[p][t] + 0.01), d = test[p][t] - ref[p][t] - swe / sw;
      rel_temporal += w * d * d / 16;
    }
    for (int t = 0; t < 8; ++t) {
      const int k = t / 3;
      const double dt = test[p][t] - test[p][0], dr = ref[p][t] - ref[p][0], e = test[p][t] - ref[p][t];
      const double w = 1 / (ref[p][t] * ref[p][t] + 0.01), de = dt - dr;
      at(S::kSumT, k) += dt, at(S::kSumR, k) += dr, at(S::kSquareT, k) += dt * dt, at(S::kSquareR, k) += dr * dr;
      at(S::kSquareE, k) += de * de, at(S::kRelative, k) += e * e * w;
      at(S::kWeight, k) += w, at(S::kWeightedE, k) += w * de, at(S::kWeightedE2, k) += w * de * de;
      sum_t += test[p][t], sum_r += ref[p][t], rel += e * e / (ref[p][t] * ref[p][t] + 0.01) / 16;
      tv_test += (test[p][t] - mt) * (test[p][t] - mt) / 14;
      tv_err += (e - me) * (e - me) / 14;
    }
    cells.AddPixel(cells.AddTile(), test[p][0], ref[p][0], sums.data(), 0.5, 1);
  }
  const TileBlockStatistics::Estimates e = cells.Evaluate({}, {});
  EXPECT_NEAR(e.tv_test, tv_test, 1e-5 * tv_test);
  EXPECT_NEAR(e.tv_err, tv_err, 1e-5 * tv_err);
  EXPECT_NEAR(*e.energy_bias, (sum_t - sum_r) / sum_r, 1e-6);
  EXPECT_NEAR(e.relmse, rel, 1e-5 * rel);
  EXPECT_NEAR(e.relmse_temporal, rel_temporal, 1e-5 * rel);
  EXPECT_NEAR(e.relmse_spatial, rel - rel_temporal, 1e-5 * rel);
  EXPECT_DOUBLE_EQ(e.flicker_index, 0.5);
  // Tile 0 twice and tile 1 not at all, blocks as they are: tile 0's numbers.
  const TileBlockStatistics::Estimates only0 = cells.Evaluate({2, 0}, {});
  double m0 = 0, v0 = 0;
  for (double v : test[0]) m0 += v / 8;
  for (double v : test[0]) v0 += (v - m0) * (v - m0) / 7;
  EXPECT_NEAR(only0.tv_test, v0, 1e-5 * v0);
}

// The replicates run in parallel batches; the intervals must not depend on
// how many threads there are, nor on where batches end (the tile count and
// the replicate count here are not multiples of anything).
TEST(MetricsIntervals, BootstrapGivesTheSameIntervalsOnAnyNumberOfThreads) {
  const std::vector<int> blocks = {3, 3, 3, 2};
  TileBlockStatistics cells(blocks);
  std::mt19937 random(11);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<float> sums(TileBlockStatistics::kCellSums * blocks.size());
  for (int tile = 0; tile < 1237; ++tile) {
    const int index = cells.AddTile();
    for (int pixel = 0; pixel < 3; ++pixel) {
      for (float& v : sums) v = u(random);
      cells.AddPixel(index, u(random), 1 + u(random), sums.data(), u(random), 1);
    }
  }
  const TileBlockStatistics::Estimates point = cells.Evaluate({}, {});
  const BootstrapSettings settings{.replicates = 203};
  const int threads = cv::getNumThreads();
  std::vector<TileBlockStatistics::Intervals> runs;
  for (int n : {1, 2, 3, 8}) {
    cv::setNumThreads(n);
    runs.push_back(cells.Bootstrap(point, settings));
  }
  cv::setNumThreads(threads);
  for (const auto& run : runs) {
    for (auto member : {&TileBlockStatistics::Intervals::tv_err, &TileBlockStatistics::Intervals::tv_ratio,
                        &TileBlockStatistics::Intervals::energy_bias, &TileBlockStatistics::Intervals::relmse,
                        &TileBlockStatistics::Intervals::relmse_temporal,
                        &TileBlockStatistics::Intervals::flicker_index}) {
      ASSERT_TRUE(run.*member && runs[0].*member);
      EXPECT_EQ((run.*member)->lo, (runs[0].*member)->lo);
      EXPECT_EQ((run.*member)->hi, (runs[0].*member)->hi);
      EXPECT_LT((run.*member)->lo, (run.*member)->hi);
    }
  }
}

// A reference with stderr.Y = s, its frames R0 + s n_t, and a test R0 +
// sigma n'_t: E's variance is sigma^2 + s^2, of which s^2 is the
// reference's noise.
TEST(MetricsIntervals, TvErrFloorRecoversTheReferenceNoiseShareFromStderrY) {
  testing::TempDir dir;
  const double sigma = 0.05, s = 0.1;  // expected share s^2 / (sigma^2 + s^2) = 0.8
  std::mt19937_64 random(11);
  std::normal_distribution<double> normal;
  std::filesystem::create_directories(dir / "test");
  std::filesystem::create_directories(dir / "ref");
  for (int t = 0; t < kFrames; ++t) {
    cv::Mat T(kSize, kSize, CV_32F), R(kSize, kSize, CV_32F), S(kSize, kSize, CV_32F, cv::Scalar(s));
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        T.at<float>(y, x) = static_cast<float>(ReferenceAt(x, y) + sigma * normal(random));
        R.at<float>(y, x) = static_cast<float>(ReferenceAt(x, y) + s * normal(random));
      }
    char name[32];
    std::snprintf(name, sizeof name, "f%04d.exr", t);
    ASSERT_TRUE(testing::WriteExrMats(dir / "test" / name, {{"R", T}, {"G", T}, {"B", T}}));
    ASSERT_TRUE(testing::WriteExrMats(dir / "ref" / name, {{"R", R}, {"G", R}, {"B", R}, {"stderr.Y", S}}));
  }
  auto with = ComputeMetrics({.test = dir / "test", .reference = dir / "ref"});
  ASSERT_TRUE(with) << with.error();
  ASSERT_TRUE(with->tv_err_floor);
  EXPECT_NEAR(*with->tv_err_floor, 0.8, 0.03);
  // The reference noise lowers tv_err's lower end by the floor, s^2.
  EXPECT_LE(with->ci95->tv_err->lo, *with->tv_err - s * s + 1e-9);
  const nlohmann::json j = ToJson(*with);
  EXPECT_TRUE(j.contains("tv_err_floor"));
  for (const char* key :
       {"tv_err", "tv_ratio", "energy_bias", "relmse", "relmse_temporal", "relmse_spatial", "flicker_index"}) {
    ASSERT_TRUE(j["ci95"].contains(key)) << key;
    ASSERT_EQ(j["ci95"][key].size(), 2u) << key;
    EXPECT_LE(j["ci95"][key][0].get<double>(), j["ci95"][key][1].get<double>()) << key;
  }
  EXPECT_EQ(j["bootstrap"]["replicates"], 1000);
  EXPECT_EQ(j["bootstrap"]["frame_block"], 3);
  EXPECT_EQ(j["bootstrap"]["tile"], 8);
  EXPECT_TRUE(j["bootstrap"].contains("seed"));

  // Without stderr.Y (another renderer's reference): intervals, no floor.
  for (int t = 0; t < kFrames; ++t) {
    char name[32];
    std::snprintf(name, sizeof name, "f%04d.exr", t);
    cv::Mat R(kSize, kSize, CV_32F);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) R.at<float>(y, x) = static_cast<float>(ReferenceAt(x, y) + s * normal(random));
    std::filesystem::create_directories(dir / "plain");
    ASSERT_TRUE(testing::WriteExrMats(dir / "plain" / name, {{"R", R}, {"G", R}, {"B", R}}));
  }
  auto without = ComputeMetrics({.test = dir / "test", .reference = dir / "plain"});
  ASSERT_TRUE(without) << without.error();
  EXPECT_FALSE(without->tv_err_floor);
  EXPECT_FALSE(ToJson(*without).contains("tv_err_floor"));
  EXPECT_TRUE(ToJson(*without).contains("ci95"));

  // Without a reference: no interval keys at all.
  auto alone = ComputeMetrics({.test = dir / "test"});
  ASSERT_TRUE(alone) << alone.error();
  const nlohmann::json k = ToJson(*alone);
  EXPECT_FALSE(k.contains("ci95"));
  EXPECT_FALSE(k.contains("bootstrap"));
  EXPECT_FALSE(k.contains("tv_err_floor"));
}

}  // namespace
}  // namespace shimmer::metrics

namespace shimmer::metrics {
namespace {

// Two tests measured against one noisy reference R0 + s n_t: A = R0 +
// sigma_a m_t, B = R0 + sigma_b m'_t. The reference's noise (F = s^2) is
// most of each tv_err, and lowers each interval's lower end by F, so their
// intervals overlap; paired, the noise cancels and the difference
// sigma_a^2 - sigma_b^2 is measured.
struct PairedRun {
  MetricsReport a, b;
};
PairedRun SimulatePair(double sigma_a, double sigma_b, double s, std::uint64_t seed) {
  MetricsAccumulator a(Setup(true)), b(Setup(true));
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  cv::Mat Ta(kSize, kSize, CV_32F), Tb(kSize, kSize, CV_32F), R(kSize, kSize, CV_32F);
  const cv::Mat stderr_y(kSize, kSize, CV_32F, cv::Scalar(s));
  for (int t = 0; t < kFrames; ++t) {
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const double r0 = ReferenceAt(x, y);
        R.at<float>(y, x) = static_cast<float>(r0 + s * normal(random));
        Ta.at<float>(y, x) = static_cast<float>(r0 + sigma_a * normal(random));
        Tb.at<float>(y, x) = static_cast<float>(r0 + sigma_b * normal(random));
      }
    a.AddFrame(Ta, R, cv::Mat(), "a", "r", stderr_y);
    b.AddFrame(Tb, R, cv::Mat(), "b", "r", stderr_y);
  }
  PairedRun run;
  EXPECT_TRUE(a.Finish(&run.a));
  EXPECT_TRUE(b.Finish(&run.b));
  return run;
}

std::optional<Interval> PairedTvErr(const PairedRun& run) {
  const BootstrapDraws &da = run.a.ci95->draws, &db = run.b.ci95->draws;
  EXPECT_EQ(da.key, db.key);
  auto d = PairedDifference(*run.a.tv_err, da.tv_err, *run.b.tv_err, db.tv_err);
  if (!d) return d;
  const double sigma =
      PairedNoiseSigma(*run.a.ref_noise, run.a.tv_test, run.b.tv_test, run.a.frames, run.a.pixels);
  const double noise = 1.959963984540054 * sigma, x = *run.a.tv_err - *run.b.tv_err;
  return Interval{x - std::hypot(x - d->lo, noise), x + std::hypot(d->hi - x, noise)};
}

TEST(PairedIntervals, SeparateWhatTheReferenceNoiseHidesAndCoverTheTrueDifference) {
  const double sigma_a = 0.05, sigma_b = 0.065, s = 0.2;
  const double truth = (sigma_a * sigma_a - sigma_b * sigma_b) * ExpectedSampleVarianceFactor(0, kFrames);
  int separated_unpaired = 0, separated_paired = 0, covered = 0;
  const int trials = 40;
  for (int trial = 0; trial < trials; ++trial) {
    const PairedRun run = SimulatePair(sigma_a, sigma_b, s, 500 + trial);
    ASSERT_TRUE(run.a.ci95 && run.b.ci95 && run.a.tv_err_floor);
    EXPECT_GT(*run.a.tv_err_floor, 0.85);  // the noise is most of tv_err
    const Interval ua = *run.a.ci95->tv_err, ub = *run.b.ci95->tv_err;
    separated_unpaired += ua.hi < ub.lo;
    const auto d = PairedTvErr(run);
    ASSERT_TRUE(d);
    separated_paired += d->hi < 0;
    covered += d->lo <= truth && truth <= d->hi;
  }
  std::printf("paired: separated %d/%d (unpaired %d), covered %d/%d\n", separated_paired, trials,
              separated_unpaired, covered, trials);
  EXPECT_EQ(separated_unpaired, 0);
  EXPECT_GE(separated_paired, trials * 9 / 10);
  EXPECT_GE(covered, trials * 85 / 100);
}

TEST(PairedIntervals, AVariantAgainstItselfIsTiedAndUnpairedRegionsDoNotPair) {
  const PairedRun run = SimulatePair(0.05, 0.05, 0.2, 3);
  const BootstrapDraws& da = run.a.ci95->draws;
  const auto self = PairedDifference(*run.a.tv_err, da.tv_err, *run.a.tv_err, da.tv_err);
  ASSERT_TRUE(self);
  EXPECT_EQ(self->lo, 0);
  EXPECT_EQ(self->hi, 0);
  // Same noise level, independent draws: tied (the interval holds 0).
  const auto d = PairedTvErr(run);
  ASSERT_TRUE(d);
  EXPECT_LT(d->lo, 0);
  EXPECT_GT(d->hi, 0);
  // Replicates of other lengths do not pair.
  Replicates shorter = da.tv_err;
  shorter.joint.pop_back();
  EXPECT_FALSE(PairedDifference(1, shorter, 1, da.tv_err));
}

TEST(PairedIntervals, DrawsSurviveTheirEncodingAndDamageIsCaught) {
  const PairedRun run = SimulatePair(0.05, 0.06, 0.1, 4);
  const BootstrapDraws& draws = run.a.ci95->draws;
  ASSERT_EQ(draws.tv_err.joint.size(), 1000u);
  const std::string bytes = EncodeDraws(draws);
  const auto back = DecodeDraws(bytes);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->key, draws.key);
  EXPECT_EQ(back->tv_err.joint, draws.tv_err.joint);
  EXPECT_EQ(back->tv_err.blocks_only, draws.tv_err.blocks_only);
  EXPECT_EQ(back->relmse.tiles_only, draws.relmse.tiles_only);
  EXPECT_FALSE(DecodeDraws(bytes.substr(0, bytes.size() - 1)));
  EXPECT_FALSE(DecodeDraws("not draws"));
}

AccumulatorSetup SetupWithoutOnePixel(bool without) {
  AccumulatorSetup setup = Setup();
  if (without) setup.region.at<unsigned char>(0, 0) = 0;
  return setup;
}

TEST(PairedIntervals, RegionsOfOtherPixelsDrawOtherwise) {
  MetricsAccumulator full(SetupWithoutOnePixel(false)), cut(SetupWithoutOnePixel(true));
  cv::Mat T(kSize, kSize, CV_32F, cv::Scalar(1)), R(kSize, kSize, CV_32F, cv::Scalar(1));
  std::mt19937_64 random(5);
  std::normal_distribution<float> normal;
  for (int t = 0; t < kFrames; ++t) {
    for (int i = 0; i < kSize * kSize; ++i) T.at<float>(i) = 1 + 0.1f * normal(random);
    full.AddFrame(T, R, cv::Mat(), "t", "r");
    cut.AddFrame(T, R, cv::Mat(), "t", "r");
  }
  MetricsReport a, b;
  ASSERT_TRUE(full.Finish(&a));
  ASSERT_TRUE(cut.Finish(&b));
  EXPECT_NE(a.ci95->draws.key, b.ci95->draws.key);
}

}  // namespace
}  // namespace shimmer::metrics
