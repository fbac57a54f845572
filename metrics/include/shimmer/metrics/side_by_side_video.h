// An MP4 where flicker can be seen: test | reference | error heatmap, one
// video frame per sequence frame, at the sequence's fps.
#pragma once

#include <filesystem>
#include <memory>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "shimmer/core/result.h"
#include "shimmer/metrics/heatmap.h"

namespace shimmer::metrics {

class SideBySideVideo {
 public:
  // Tries the H.264 fourcc (avc1) first, then MPEG-4 Part 2 (mp4v): whichever
  // the installed OpenCV/FFmpeg can encode. Without a reference the panels are
  // test | |T_t - T_{t-1}|.
  static Result<std::unique_ptr<SideBySideVideo>> Open(const std::filesystem::path& file, int width, int height,
                                                       double fps, bool with_reference);
  ~SideBySideVideo();

  // Luminance frames (CV_32F). Display only: tone-mapped with x/(1+x) and
  // sRGB-encoded here; the metrics never see this. The error panel's scale is
  // fixed by the first frame (99th percentile of |E|) so that flicker shows as
  // colour changing over time, not as a rescaled image.
  Status AddFrame(const cv::Mat& test, const cv::Mat& reference_or_previous);

  // Closes the file and renames it into place.
  Status Finish();
  const char* fourcc_name() const { return fourcc_name_; }

 private:
  SideBySideVideo() = default;
  std::filesystem::path file_, temporary_;
  cv::VideoWriter writer_;
  bool with_reference_ = true;
  int width_ = 0, height_ = 0;
  cv::Size frame_size_;
  HeatmapRange error_range_;
  bool have_range_ = false;
  bool finished_ = false;
  const char* fourcc_name_ = "";
};

}  // namespace shimmer::metrics
