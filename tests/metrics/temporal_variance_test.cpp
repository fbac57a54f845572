#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "shimmer/metrics/temporal_variance.h"

namespace shimmer::metrics {
namespace {

double TwoPassVariance(const std::vector<double>& x) {
  double mean = 0;
  for (double v : x) mean += v;
  mean /= x.size();
  double ss = 0;
  for (double v : x) ss += (v - mean) * (v - mean);
  return ss / (x.size() - 1);
}

TEST(TemporalMoments, MatchesTwoPassUnbiasedVariance) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(3.0, 2.0);
  std::vector<double> x(100);
  TemporalMoments m(1, 1);
  for (double& v : x) m.Add(0, v = noise(rng));
  EXPECT_EQ(m.count(0), 100u);
  EXPECT_NEAR(m.variance(0), TwoPassVariance(x), 1e-12);
}

TEST(TemporalMoments, ConstantSeriesHasZeroVariance) {
  TemporalMoments m(2, 1);
  for (int t = 0; t < 50; ++t) m.Add(0, 0.1), m.Add(1, 1e6);
  EXPECT_EQ(m.variance(0), 0.0);
  EXPECT_EQ(m.variance(1), 0.0);
}

TEST(TemporalMoments, FewerThanTwoSamplesGiveZero) {
  TemporalMoments m(1, 1);
  EXPECT_EQ(m.variance(0), 0.0);
  m.Add(0, 5.0);
  EXPECT_EQ(m.variance(0), 0.0);
}

// A highlight at 1e4 flickering by +-1e-3: sum-of-squares in double loses it
// (1e8 vs 1e-6 is 14 digits apart), Welford keeps it.
TEST(TemporalMoments, KeepsSmallFlickerOnABrightHighlight) {
  TemporalMoments m(1, 1);
  const int n = 1000;
  for (int t = 0; t < n; ++t) m.Add(0, 1e4 + (t % 2 ? 1e-3 : -1e-3));
  const double expected = 1e-6 * n / (n - 1);
  EXPECT_NEAR(m.variance(0), expected, expected * 1e-6);
}

TEST(TemporalMoments, ChanMergeEqualsOnePass) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-5, 20);
  const int w = 3, h = 2;
  TemporalMoments all(w, h), first(w, h), second(w, h);
  for (int t = 0; t < 37; ++t)
    for (int i = 0; i < w * h; ++i) {
      double v = u(rng) * (i + 1);
      all.Add(i, v);
      (t < 13 ? first : second).Add(i, v);
    }
  first.Merge(second);
  for (int i = 0; i < w * h; ++i) {
    EXPECT_EQ(first.count(i), all.count(i));
    EXPECT_NEAR(first.mean(i), all.mean(i), 1e-12 * std::abs(all.mean(i)) + 1e-12);
    EXPECT_NEAR(first.variance(i), all.variance(i), 1e-10 * all.variance(i));
  }
}

TEST(TemporalMoments, MergeIntoEmptyCopies) {
  TemporalMoments a(1, 1), b(1, 1);
  b.Add(0, 1), b.Add(0, 3);
  a.Merge(b);
  EXPECT_EQ(a.count(0), 2u);
  EXPECT_DOUBLE_EQ(a.mean(0), 2.0);
  EXPECT_DOUBLE_EQ(a.variance(0), 2.0);
}

TEST(TemporalMoments, MergeRejectsDifferentSizes) {
  TemporalMoments a(2, 2), b(1, 2);
  EXPECT_THROW(a.Merge(b), std::invalid_argument);
}

}  // namespace
}  // namespace shimmer::metrics
