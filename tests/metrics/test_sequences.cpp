#include "test_sequences.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "shimmer/metrics/exr_sequence.h"

namespace shimmer::metrics::testing {

void WriteSequence(const std::filesystem::path& dir, const SequenceSpec& spec) {
  std::filesystem::create_directories(dir);
  for (int t = 0; t < spec.frames; ++t) {
    cv::Mat v(spec.height, spec.width, CV_32F);
    for (int y = 0; y < spec.height; ++y)
      for (int x = 0; x < spec.width; ++x) v.at<float>(y, x) = spec.value(t, x, y);
    std::vector<MatChannel> channels;
    switch (spec.layout) {
      case Layout::kBeautyRgb: channels = {{"R", v}, {"G", v}, {"B", v}}; break;
      case Layout::kBeautyRgbHalf:
        channels = {{"R", v, true}, {"G", v, true}, {"B", v, true}, {"A", cv::Mat::ones(v.size(), CV_32F), true}};
        break;
      case Layout::kSpecularLayer: {
        cv::Mat half_grey(v.size(), CV_32F, cv::Scalar(0.5));
        channels = {{"R", half_grey},  {"G", half_grey},  {"B", half_grey},
                    {"specular.R", v}, {"specular.G", v}, {"specular.B", v}};
        break;
      }
      case Layout::kLuminanceY: channels = {{"Y", v}}; break;
    }
    if (spec.motion) {
      cv::Mat mx(v.size(), CV_32F), my(v.size(), CV_32F);
      for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x) {
          cv::Vec2f m = spec.motion(t, x, y);
          mx.at<float>(y, x) = m[0];
          my.at<float>(y, x) = m[1];
        }
      channels.push_back({"motion.X", mx});
      channels.push_back({"motion.Y", my});
    }
    char name[64];
    std::snprintf(name, sizeof name, "%s%04d.exr", spec.prefix.c_str(), t);
    if (Status s = WriteExrMats(dir / name, channels); !s) throw std::runtime_error(s.error());
  }
}

Status WriteExrMats(const std::filesystem::path& file, const std::vector<MatChannel>& channels,
                    ExrCompression compression) {
  if (channels.empty()) return Status::Failure(file.string() + ": no channels");
  std::vector<ExrPlane> planes;
  for (const MatChannel& c : channels) planes.push_back(PlaneOf(c.name, c.plane, c.half));
  return WriteExr(file, channels[0].plane.cols, channels[0].plane.rows, planes, compression);
}

}  // namespace shimmer::metrics::testing
