// Reference-free temporal error: how much frame t differs from frame t-1
// carried along the renderer's motion vectors. A stable image scores ~0 under
// any camera motion; flicker and crawling highlights do not.
#pragma once

#include <opencv2/core.hpp>

namespace shimmer::metrics {

// T_{t-1} resampled at p + motion_t(p) (bilinear): motion points from a pixel
// of frame t to where the same surface point was in frame t-1, in pixels
// (the renderer's motion.X/Y convention). Where the source footprint leaves
// the frame, or touches a non-finite pixel, the result is NaN: those pixels
// count as occluded.
cv::Mat WarpPrevious(const cv::Mat& previous, const cv::Mat& motion);
// The same into `warped`, with `map` as scratch: both keep their memory from
// call to call (a fresh 3 MiB a frame at 512x512 meant fresh page faults).
void WarpPrevious(const cv::Mat& previous, const cv::Mat& motion, cv::Mat& map, cv::Mat& warped);

// Accumulates mean |T_t - warp(T_{t-1})| over non-occluded pixels of a region.
class WarpError {
 public:
  // `region` (CV_8U, nonzero = in) and `excluded` (CV_8U or empty) select pixels.
  void AddFrame(const cv::Mat& previous, const cv::Mat& current, const cv::Mat& motion, const cv::Mat& region,
                const cv::Mat& excluded);
  bool empty() const { return count_ == 0; }
  double mean() const { return count_ ? sum_ / count_ : 0.0; }
  long long samples() const { return count_; }

 private:
  double sum_ = 0;
  long long count_ = 0;
  cv::Mat map_, warped_;
};

}  // namespace shimmer::metrics
