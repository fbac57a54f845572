// A sequence of EXR frames from any renderer: a directory of *.exr (sorted by
// file name) or a sequence.json. Frames may be single-part with plain R,G,B(,A)
// or layered channel names ("specular.R"), or multi-part with one layer per
// part; half or float. What the metrics read is the linear luminance of one
// layer, and optionally the motion.X/Y vectors.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "shimmer/core/exr_output.h"
#include "shimmer/core/result.h"

namespace shimmer::metrics {

// Rec. 709 / sRGB primaries luminance weights (ITU-R BT.709-6, item 3.2).
inline constexpr double kLumaR = 0.2126, kLumaG = 0.7152, kLumaB = 0.0722;

// The name users type for the unprefixed R,G,B channels.
inline constexpr const char* kBeautyLayer = "beauty";

struct SequenceRequest {
  std::string layer;          // empty: "specular" when present, else beauty
  std::optional<double> fps;  // used when sequence.json has none
};

struct ExrSequence {
  std::filesystem::path source;               // the directory or sequence.json given
  std::vector<std::filesystem::path> frames;  // sorted
  int width = 0, height = 0;
  double fps = 60;
  std::string fps_source;           // "sequence.json", "--fps" or "default"
  std::string layer;                // chosen layer, "beauty" for unprefixed R,G,B
  std::vector<std::string> layers;  // every layer with luminance in frame 0
  bool has_motion = false;          // every frame has motion.X and motion.Y
  bool has_stderr = false;          // every frame has stderr.Y (shimmer's references)
  std::vector<std::string> warnings;
};

// Lists and checks every frame's header (size, layer, channels), so that a bad
// frame is reported before any computing starts.
Result<ExrSequence> OpenSequence(const std::filesystem::path& path, const SequenceRequest& request);

struct LuminanceFrame {
  cv::Mat luminance;  // CV_32F, height x width, linear
  cv::Mat motion;     // CV_32FC2 (x, y) in pixels towards the previous frame; empty if not read
  cv::Mat stderr_y;   // CV_32F standard error of the luminance (stderr.Y); empty if not read
};

// Reads one frame's luminance of `layer` (and motion.X/Y, stderr.Y when asked).
Result<LuminanceFrame> ReadFrame(const std::filesystem::path& file, const std::string& layer, int width, int height,
                                 bool with_motion, bool with_stderr = false);

// The planes a frame's channels are decoded into before they are combined
// (R, G, B into luminance; motion.X, motion.Y into one two-channel plane).
struct FrameScratch {
  cv::Mat r, g, b, motion_x, motion_y;
};

// ReadFrame into `frame`, whose planes (and `scratch`'s) are reused where
// their size and type already fit: a pass reads every frame of a sequence at
// one size, and fresh planes for each cost page faults that, at 1080p, took
// longer than the arithmetic on them (bench/metrics_bench). `frame`'s planes
// must not be shared with anything that still reads them.
Status ReadFrameInto(const std::filesystem::path& file, const std::string& layer, int width, int height,
                     bool with_motion, bool with_stderr, FrameScratch& scratch, LuminanceFrame& frame);

// Any single-channel image used as a mask (EXR or anything OpenCV reads):
// nonzero = inside. Returned as CV_8U 0/1.
Result<cv::Mat> ReadMask(const std::filesystem::path& file, int width, int height);

// A continuous CV_32F plane as a channel for shimmer::WriteExr (the one EXR
// writer, shimmer/core/exr_output.h); the plane must outlive the write.
ExrPlane PlaneOf(std::string name, const cv::Mat& plane, bool half = false);

}  // namespace shimmer::metrics
