#include "shimmer/metrics/temporal_variance.h"

#include <stdexcept>

namespace shimmer::metrics {

TemporalMoments::TemporalMoments(int width, int height)
    : width_(width),
      height_(height),
      count_(static_cast<size_t>(width) * height, 0),
      mean_(count_.size(), 0.0),
      m2_(count_.size(), 0.0) {}

void TemporalMoments::Merge(const TemporalMoments& other) {
  if (other.width_ != width_ || other.height_ != height_)
    throw std::invalid_argument("TemporalMoments::Merge: different frame sizes");
  cv::parallel_for_(cv::Range(0, height_), [&](const cv::Range& rows) {
    for (size_t i = static_cast<size_t>(rows.start) * width_; i < static_cast<size_t>(rows.end) * width_; ++i) {
      const double na = count_[i], nb = other.count_[i];
      if (nb == 0) continue;
      const double n = na + nb;
      const double delta = other.mean_[i] - mean_[i];
      mean_[i] += delta * nb / n;
      m2_[i] += other.m2_[i] + delta * delta * na * nb / n;
      count_[i] += other.count_[i];
    }
  });
}

cv::Mat TemporalMoments::MeanMap() const {
  cv::Mat out(height_, width_, CV_64F);
  std::copy(mean_.begin(), mean_.end(), out.ptr<double>());
  return out;
}

cv::Mat TemporalMoments::VarianceMap() const {
  cv::Mat out(height_, width_, CV_64F);
  double* dst = out.ptr<double>();
  for (size_t i = 0; i < count_.size(); ++i) dst[i] = variance(i);
  return out;
}

}  // namespace shimmer::metrics
