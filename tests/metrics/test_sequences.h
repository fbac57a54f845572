// Synthetic EXR sequences for the metrics tests: written into a temporary
// directory that the test owns and removes.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include <opencv2/core.hpp>

#include "shimmer/core/exr_output.h"
#include "temp_dir.h"

namespace shimmer::metrics::testing {

using shimmer::testing::TempDir;

// Value of pixel (x, y) at frame t.
using PixelFunction = std::function<float(int t, int x, int y)>;

enum class Layout {
  kBeautyRgb,      // R,G,B float
  kBeautyRgbHalf,  // R,G,B,A half
  kSpecularLayer,  // R,G,B beauty (constant 0.5) + specular.R/G/B carrying the value
  kLuminanceY,     // a single Y channel
};

struct SequenceSpec {
  int frames = 8, width = 32, height = 32;
  Layout layout = Layout::kBeautyRgb;
  PixelFunction value;
  // Optional motion vectors (pixels towards the previous frame).
  std::function<cv::Vec2f(int t, int x, int y)> motion;
  std::string prefix = "frame_";
};

// Writes frames <prefix>0000.exr ... into `dir` (created). Grey pixels: R = G = B =
// value, so luminance == value exactly (the weights sum to 1).
void WriteSequence(const std::filesystem::path& dir, const SequenceSpec& spec);

// One named CV_32F plane of a test EXR.
struct MatChannel {
  std::string name;
  cv::Mat plane;
  bool half = false;
};
// Through shimmer::WriteExr, the one EXR writer; every plane the same size.
Status WriteExrMats(const std::filesystem::path& file, const std::vector<MatChannel>& channels,
                    ExrCompression compression = ExrCompression::kZip);

}  // namespace shimmer::metrics::testing
