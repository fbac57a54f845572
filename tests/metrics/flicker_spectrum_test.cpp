#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "shimmer/metrics/flicker_spectrum.h"
#include "shimmer/metrics/temporal_sensitivity.h"

namespace shimmer::metrics {
namespace {

constexpr double kPi = std::numbers::pi;

double Integral(const std::vector<double>& psd, double fs, int length) {
  double s = 0;
  for (double p : psd) s += p * fs / length;
  return s;
}

TEST(PeriodicHann, IsScipysPeriodicWindow) {
  auto w = PeriodicHann(8);
  ASSERT_EQ(w.size(), 8u);
  EXPECT_DOUBLE_EQ(w[0], 0.0);
  EXPECT_DOUBLE_EQ(w[4], 1.0);  // periodic: the peak is at L/2, no closing zero
  EXPECT_NEAR(w[2], 0.5, 1e-15);
  EXPECT_NEAR(w[7], w[1], 1e-15);
}

TEST(WelchSegments, CountsLikeScipy) {
  EXPECT_EQ(WelchSegmentCount(64, 64), 1);
  EXPECT_EQ(WelchSegmentCount(95, 64), 1);  // tail shorter than a step is dropped
  EXPECT_EQ(WelchSegmentCount(96, 64), 2);
  EXPECT_EQ(WelchSegmentCount(40, 16), 4);
  EXPECT_EQ(WelchSegmentCount(37, 15), 3);  // odd L: step = L - L/2 = 8
  EXPECT_EQ(WelchSegmentCount(10, 16), 0);
}

TEST(WelchFrequencies, OneSidedBins) {
  auto f = WelchFrequencies(16, 60);
  ASSERT_EQ(f.size(), 9u);
  EXPECT_DOUBLE_EQ(f[1], 3.75);
  EXPECT_DOUBLE_EQ(f.back(), 30.0);
  EXPECT_EQ(WelchFrequencies(15, 60).size(), 8u);
}

// Parseval: with density scaling, sum_k psd_k * fs/L over the one-sided bins is
// exactly the mean over segments of sum (x - mean)^2 w^2 / sum w^2, the
// window-weighted mean-removed variance of each segment.
TEST(FlickerSpectrum, ParsevalIntegralIsWindowWeightedVariance) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int length : {16, 15}) {
    const int n = 100;
    const double fs = 48;
    std::vector<double> x(n);
    for (int t = 0; t < n; ++t) x[t] = 2.0 + noise(rng) + 0.5 * std::sin(0.3 * t);
    for (double& v : x) v = static_cast<float>(v);  // the spectrum stores float samples
    const auto psd = WelchPsd(x, fs, length);
    const auto w = PeriodicHann(length);
    double sum_w2 = 0;
    for (double v : w) sum_w2 += v * v;
    const int step = length - length / 2, segments = WelchSegmentCount(n, length);
    double expected = 0;
    for (int s = 0; s < segments; ++s) {
      double mean = 0;
      for (int j = 0; j < length; ++j) mean += x[s * step + j];
      mean /= length;
      for (int j = 0; j < length; ++j) expected += std::pow((x[s * step + j] - mean) * w[j], 2) / sum_w2;
    }
    expected /= segments;
    EXPECT_NEAR(Integral(psd, fs, length), expected, 1e-9 * expected) << "L = " << length;
  }
}

// A sinusoid centred on bin k0 with amplitude A: a periodic Hann window puts
// A^2 L / (3 fs) in bin k0 and A^2 L / (12 fs) in each neighbour (the window's
// spectrum has exactly three nonzero bins), nothing elsewhere, and the integral
// is A^2 / 2, the sinusoid's variance.
TEST(FlickerSpectrum, SinusoidLandsInItsBinWithItsPower) {
  const int length = 32, n = 96, k0 = 5;
  const double fs = 60, amplitude = 0.75;
  std::vector<double> x(n);
  for (int t = 0; t < n; ++t) x[t] = 1.0 + amplitude * std::sin(2 * kPi * k0 * t / length + 0.3);
  const auto psd = WelchPsd(x, fs, length);
  const double a2 = amplitude * amplitude;
  EXPECT_NEAR(psd[k0], a2 * length / (3 * fs), 1e-6 * a2 * length / fs);
  EXPECT_NEAR(psd[k0 - 1], a2 * length / (12 * fs), 1e-6 * a2 * length / fs);
  EXPECT_NEAR(psd[k0 + 1], a2 * length / (12 * fs), 1e-6 * a2 * length / fs);
  for (size_t k = 0; k < psd.size(); ++k)
    if (std::abs(static_cast<int>(k) - k0) > 1) {
      EXPECT_LT(psd[k], 1e-9) << "bin " << k;
    }
  EXPECT_NEAR(Integral(psd, fs, length), a2 / 2, 1e-6);
  EXPECT_DOUBLE_EQ(WelchFrequencies(length, fs)[k0], k0 * fs / length);
}

// White noise of variance s^2 has the flat one-sided density 2 s^2 / fs.
TEST(FlickerSpectrum, WhiteNoiseIsFlatAtTheRightLevel) {
  std::mt19937 rng(5);
  const double sigma = 0.2, fs = 50;
  const int length = 16, pixels = 4000, frames = 64;
  std::normal_distribution<float> noise(0.0f, static_cast<float>(sigma));
  std::vector<int> indices(pixels);
  for (int i = 0; i < pixels; ++i) indices[i] = i;
  FlickerSpectrum spectrum(indices, length, fs);
  cv::Mat frame(1, pixels, CV_32F);
  for (int t = 0; t < frames; ++t) {
    for (int i = 0; i < pixels; ++i) frame.at<float>(0, i) = noise(rng);
    spectrum.AddFrame(frame, cv::Mat());
  }
  EXPECT_EQ(spectrum.segments(), WelchSegmentCount(frames, length));
  const auto psd = spectrum.Psd();
  const double level = 2 * sigma * sigma / fs;
  // Bins away from DC: constant detrend removes the mean (and a window-
  // weighted share of the lowest bins), and Nyquist is not doubled.
  for (int k = 2; k < length / 2; ++k) EXPECT_NEAR(psd[k], level, 0.05 * level) << "bin " << k;
  EXPECT_NEAR(psd[length / 2], level / 2, 0.05 * level);
}

TEST(FlickerSpectrum, ExcludedPixelsDoNotContribute) {
  FlickerSpectrum spectrum({0, 1}, 4, 10);
  cv::Mat frame(1, 2, CV_32F), excluded = cv::Mat::zeros(1, 2, CV_8U);
  excluded.at<uint8_t>(0, 1) = 1;
  for (int t = 0; t < 4; ++t) {
    frame.at<float>(0, 0) = static_cast<float>(t % 2);
    frame.at<float>(0, 1) = 1000.0f * t;  // would dominate if it counted
    spectrum.AddFrame(frame, excluded);
  }
  auto alone = WelchPsd({0, 1, 0, 1}, 10, 4);
  auto psd = spectrum.Psd();
  for (size_t k = 0; k < psd.size(); ++k) EXPECT_NEAR(psd[k], alone[k], 1e-12);
}

// Cross-check against scipy 1.10.1, produced by hand with
//   n = np.arange(40); x = np.sin(0.7*n) + 0.3*np.cos(2.1*n + 0.4) + 0.01*n**2
//   scipy.signal.welch(x, fs=30, window='hann', nperseg=16, noverlap=8,
//                      detrend='constant', scaling='density')[1]
//   scipy.signal.welch(x[:37], fs=24, window='hann', nperseg=15, noverlap=7, ...)[1]
// The series is regenerated here; tolerance is float precision (samples are
// stored as float).
TEST(FlickerSpectrum, MatchesScipyWelch) {
  std::vector<double> x(40);
  for (int n = 0; n < 40; ++n) x[n] = std::sin(0.7 * n) + 0.3 * std::cos(2.1 * n + 0.4) + 0.01 * n * n;
  const std::vector<double> even = {0.0070738958447897236, 0.45999093006842029,    0.16796071297263221,
                                    0.025335232334966228,  0.0016799744188049409,  0.013379048519049511,
                                    0.009275945640623064,  0.00014704923261399486, 3.7185815756954353e-06};
  auto psd = WelchPsd(x, 30, 16);
  ASSERT_EQ(psd.size(), even.size());
  for (size_t k = 0; k < psd.size(); ++k) EXPECT_NEAR(psd[k], even[k], 2e-6 * 0.46) << "bin " << k;

  const std::vector<double> odd = {0.016586359658972916,  0.35090398037176196,   0.18870983237355751,
                                   0.017200319607323558,  0.0047461047299994672, 0.018866734248224683,
                                   0.0048717703540978796, 1.3797855249009213e-06};
  psd = WelchPsd(std::vector<double>(x.begin(), x.begin() + 37), 24, 15);
  ASSERT_EQ(psd.size(), odd.size());
  for (size_t k = 0; k < psd.size(); ++k) EXPECT_NEAR(psd[k], odd[k], 2e-6 * 0.35) << "bin " << k;
}

TEST(BandPowers, SplitTheIntegralAtTwoAndEightHertz) {
  // L = 30 at 60 fs: bins every 2 Hz -> [0] low, [1..3] mid, [4..15] high.
  std::vector<double> f = WelchFrequencies(30, 60), psd(f.size(), 1.0);
  BandPowers b = IntegrateBands(f, psd);
  EXPECT_DOUBLE_EQ(b.low, 2.0);
  EXPECT_DOUBLE_EQ(b.mid, 6.0);
  EXPECT_DOUBLE_EQ(b.high, 24.0);
}

TEST(WatsonTemporalGain, BandPassPeakingNearEightHertz) {
  EXPECT_NEAR(WatsonTemporalGain(8.5), 1.0, 1e-3);
  double best_f = 0, best = 0;
  for (double f = 0.5; f < 40; f += 0.1)
    if (WatsonTemporalGain(f) > best) best = WatsonTemporalGain(f), best_f = f;
  EXPECT_NEAR(best, 1.0, 1e-4);  // a 0.1 Hz grid straddles the exact peak
  EXPECT_GT(best_f, 7.0);
  EXPECT_LT(best_f, 10.0);
  EXPECT_LT(WatsonTemporalGain(0.0), 0.2);    // sustained light is not flicker
  EXPECT_LT(WatsonTemporalGain(60.0), 0.01);  // beyond fusion
  EXPECT_GT(WatsonTemporalGain(2.0), WatsonTemporalGain(0.5));
  EXPECT_GT(WatsonTemporalGain(15.0), WatsonTemporalGain(30.0));
}

TEST(FlickerIndex, WeightsPowerByTheSquaredGain) {
  std::vector<double> f = WelchFrequencies(64, 64), psd(f.size(), 0.0);
  psd[8] = 1.0;  // all power at 8 Hz, visible
  const double at8 = FlickerIndex(f, psd);
  EXPECT_NEAR(at8, std::pow(WatsonTemporalGain(8.0), 2) * 1.0, 1e-12);
  psd[8] = 0, psd[30] = 1.0;  // same power at 30 Hz: much less visible
  EXPECT_LT(FlickerIndex(f, psd), 0.05 * at8);
}

}  // namespace
}  // namespace shimmer::metrics
