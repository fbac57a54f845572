#include "shimmer/metrics/energy_bias.h"

namespace shimmer::metrics {

std::optional<double> RelativeBias(double sum_test, double sum_reference) {
  if (sum_reference == 0) return std::nullopt;
  return (sum_test - sum_reference) / sum_reference;
}

cv::Mat EnergyBiasMap(const cv::Mat& mean_test, const cv::Mat& mean_reference, const cv::Mat& region,
                      const cv::Mat& excluded) {
  CV_Assert(mean_test.type() == CV_64F && mean_reference.type() == CV_64F);
  cv::Mat out = cv::Mat::zeros(mean_test.size(), CV_32F);
  for (int y = 0; y < out.rows; ++y) {
    const double* t = mean_test.ptr<double>(y);
    const double* r = mean_reference.ptr<double>(y);
    const uint8_t* in = region.ptr<uint8_t>(y);
    const uint8_t* drop = excluded.empty() ? nullptr : excluded.ptr<uint8_t>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x) {
      if (!in[x] || (drop && drop[x]) || r[x] == 0) continue;
      o[x] = static_cast<float>((t[x] - r[x]) / r[x]);
    }
  }
  return out;
}

}  // namespace shimmer::metrics
