#include "shimmer/metrics/highlight_mask.h"

#include <algorithm>

#include <opencv2/imgproc.hpp>

namespace shimmer::metrics {

namespace {

void AddAboveThreshold(const cv::Mat& luminance, double threshold, cv::Mat& mask) {
  // NaN > t is false, +Inf counts as a (broken) highlight only if finite:
  // keep the mask to finite values so Inf pixels do not grow the region.
  cv::Mat above = (luminance > threshold) & (luminance < std::numeric_limits<float>::infinity());
  mask |= above;
}

cv::Mat Dilate(const cv::Mat& mask, int radius) {
  if (radius <= 0) return mask;
  cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
  cv::Mat out;
  cv::dilate(mask, out, kernel);
  return out;
}

}  // namespace

Result<cv::Mat> BuildHighlightMask(const ExrSequence& sequence, const HighlightMaskOptions& options) {
  const bool has_specular =
      std::find(sequence.layers.begin(), sequence.layers.end(), "specular") != sequence.layers.end();
  const std::string layer = has_specular ? "specular" : sequence.layer;
  cv::Mat mask = cv::Mat::zeros(sequence.height, sequence.width, CV_8U);
  for (const auto& file : sequence.frames) {
    auto frame = ReadFrame(file, layer, sequence.width, sequence.height, false);
    if (!frame) return Result<cv::Mat>::Failure(frame.error());
    AddAboveThreshold(frame->luminance, options.threshold, mask);
  }
  return cv::Mat(Dilate(mask, options.dilate_radius) / 255);
}

}  // namespace shimmer::metrics
