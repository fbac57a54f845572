#include "shimmer/metrics/temporal_sensitivity.h"

#include <cmath>
#include <complex>
#include <numbers>

namespace shimmer::metrics {

namespace {

constexpr double kTau = 4.94e-3;  // s
constexpr double kKappa = 1.33;
constexpr int kN1 = 9, kN2 = 10;
constexpr double kZeta = 0.9;

double UnnormalizedGain(double f) {
  const std::complex<double> s1(1.0, 2.0 * std::numbers::pi * f * kTau);
  const std::complex<double> s2(1.0, 2.0 * std::numbers::pi * f * kKappa * kTau);
  return std::abs(std::pow(s1, -kN1) - kZeta * std::pow(s2, -kN2));
}

// The peak, found once by golden-section search on [1, 30] Hz (the gain is
// unimodal there), so that the weighting is 1 at the most visible frequency.
double PeakGain() {
  static const double peak = [] {
    double a = 1, b = 30;
    const double g = (std::sqrt(5.0) - 1) / 2;
    for (int i = 0; i < 100; ++i) {
      double c = b - g * (b - a), d = a + g * (b - a);
      if (UnnormalizedGain(c) > UnnormalizedGain(d))
        b = d;
      else
        a = c;
    }
    return UnnormalizedGain((a + b) / 2);
  }();
  return peak;
}

}  // namespace

double WatsonTemporalGain(double frequency_hz) { return UnnormalizedGain(std::abs(frequency_hz)) / PeakGain(); }

double FlickerIndex(const std::vector<double>& freq_hz, const std::vector<double>& psd) {
  if (freq_hz.size() < 2) return 0;
  const double df = freq_hz[1] - freq_hz[0];
  double sum = 0;
  for (size_t k = 0; k < psd.size(); ++k) {
    const double h = WatsonTemporalGain(freq_hz[k]);
    sum += h * h * psd[k] * df;
  }
  return sum;
}

}  // namespace shimmer::metrics
