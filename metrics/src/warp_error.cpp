#include "shimmer/metrics/warp_error.h"

#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

namespace shimmer::metrics {

cv::Mat WarpPrevious(const cv::Mat& previous, const cv::Mat& motion) {
  cv::Mat map, warped;
  WarpPrevious(previous, motion, map, warped);
  return warped;
}

void WarpPrevious(const cv::Mat& previous, const cv::Mat& motion, cv::Mat& map, cv::Mat& warped) {
  CV_Assert(previous.type() == CV_32F && motion.type() == CV_32FC2 && previous.size() == motion.size());
  map.create(motion.size(), CV_32FC2);
  cv::parallel_for_(cv::Range(0, motion.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const cv::Vec2f* m = motion.ptr<cv::Vec2f>(y);
      cv::Vec2f* out = map.ptr<cv::Vec2f>(y);
      for (int x = 0; x < motion.cols; ++x) out[x] = cv::Vec2f(x + m[x][0], y + m[x][1]);
    }
  });
  // NaN as the border: a bilinear tap outside the frame poisons the sample,
  // which then counts as occluded instead of blending with a made-up value.
  cv::remap(previous, warped, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
            cv::Scalar(std::numeric_limits<double>::quiet_NaN()));
}

void WarpError::AddFrame(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& motion, const cv::Mat& region,
                         const cv::Mat& excluded) {
  WarpPrevious(previous, motion, map_, warped_);
  const cv::Mat& warped = warped_;
  for (int y = 0; y < current.rows; ++y) {
    const float* c = current.ptr<float>(y);
    const float* w = warped.ptr<float>(y);
    const uint8_t* in = region.ptr<uint8_t>(y);
    const uint8_t* drop = excluded.empty() ? nullptr : excluded.ptr<uint8_t>(y);
    for (int x = 0; x < current.cols; ++x) {
      if (!in[x] || (drop && drop[x])) continue;
      const double d = static_cast<double>(c[x]) - w[x];
      if (!std::isfinite(d)) continue;
      sum_ += std::abs(d);
      ++count_;
    }
  }
}

}  // namespace shimmer::metrics
