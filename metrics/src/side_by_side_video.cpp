#include "shimmer/metrics/side_by_side_video.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "shimmer/core/atomic_file.h"

namespace shimmer::metrics {

namespace {

cv::Mat DisplayGrey(const cv::Mat& luminance) {
  cv::Mat out(luminance.size(), CV_8UC3);
  for (int y = 0; y < luminance.rows; ++y) {
    const float* l = luminance.ptr<float>(y);
    cv::Vec3b* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < luminance.cols; ++x) {
      double v = std::isfinite(l[x]) ? std::max(0.0f, l[x]) : 0.0;
      v = v / (1.0 + v);  // Reinhard: keeps highlights from clipping flat
      v = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;  // sRGB OETF
      uchar g = cv::saturate_cast<uchar>(255.0 * v);
      o[x] = cv::Vec3b(g, g, g);
    }
  }
  return out;
}

}  // namespace

Result<std::unique_ptr<SideBySideVideo>> SideBySideVideo::Open(const std::filesystem::path& file, int width, int height,
                                                               double fps, bool with_reference) {
  using R = Result<std::unique_ptr<SideBySideVideo>>;
  std::error_code ec;
  // A missing directory is the user's typo, not a tree to create.
  if (!file.parent_path().empty() && !std::filesystem::is_directory(file.parent_path(), ec))
    return R::Failure(file.string() + ": the directory " + file.parent_path().string() + " does not exist");
  std::unique_ptr<SideBySideVideo> video(new SideBySideVideo());
  video->file_ = file;
  video->temporary_ = TemporaryPathFor(file);
  video->with_reference_ = with_reference;
  video->width_ = width;
  video->height_ = height;
  const int panels = with_reference ? 3 : 2;
  // Encoders want even sizes (4:2:0 chroma); pad by one pixel if needed.
  video->frame_size_ = cv::Size((panels * width + 1) / 2 * 2, (height + 1) / 2 * 2);
  struct Codec {
    const char* name;
    int fourcc;
  };
  const Codec codecs[] = {{"avc1", cv::VideoWriter::fourcc('a', 'v', 'c', '1')},
                          {"mp4v", cv::VideoWriter::fourcc('m', 'p', '4', 'v')}};
  for (const Codec& c : codecs) {
    try {
      if (video->writer_.open(video->temporary_.string(), cv::CAP_FFMPEG, c.fourcc, fps, video->frame_size_, true)) {
        video->fourcc_name_ = c.name;
        return R(std::move(video));
      }
    } catch (const cv::Exception&) {
    }
  }
  std::filesystem::remove(video->temporary_, ec);
  return R::Failure(file.string() +
                    ": OpenCV cannot encode MP4 here (tried fourcc avc1 and mp4v through FFmpeg); "
                    "install an OpenCV built with FFmpeg (libopencv-videoio with libavcodec)");
}

SideBySideVideo::~SideBySideVideo() {
  if (!finished_) {
    writer_.release();
    std::error_code ec;
    std::filesystem::remove(temporary_, ec);
  }
}

Status SideBySideVideo::AddFrame(const cv::Mat& test, const cv::Mat& other) {
  cv::Mat error;
  if (with_reference_) {
    error = test - other;
  } else {
    error = cv::abs(test - other);
  }
  if (!have_range_) {
    error_range_ = AutoRange(error, cv::Mat(), with_reference_ ? HeatmapScaling::kSigned : HeatmapScaling::kLog);
    have_range_ = true;
  }
  cv::Mat frame(frame_size_, CV_8UC3, cv::Scalar(0, 0, 0));
  DisplayGrey(test).copyTo(frame(cv::Rect(0, 0, width_, height_)));
  int x = width_;
  if (with_reference_) {
    DisplayGrey(other).copyTo(frame(cv::Rect(x, 0, width_, height_)));
    x += width_;
  }
  ColourMap(error, with_reference_ ? HeatmapScaling::kSigned : HeatmapScaling::kLog, error_range_)
      .copyTo(frame(cv::Rect(x, 0, width_, height_)));
  writer_.write(frame);
  return Ok();
}

Status SideBySideVideo::Finish() {
  writer_.release();
  finished_ = true;
  return CommitFile(temporary_, file_);
}

}  // namespace shimmer::metrics
