// An MP4 where flicker can be seen and compared: a grid of up to 9 labelled
// tiles, the reference first and up to 8 test sequences, each test above its
// signed error against the reference on one diverging colour scale that the
// legend under the reference spells out (range and sign). Without a
// reference the lower panel is |T_t - T_{t-1}| on a log scale and the first
// tile holds the legend alone. Frames may be repeated for slow motion.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "shimmer/core/result.h"
#include "shimmer/metrics/exr_sequence.h"
#include "shimmer/metrics/heatmap.h"

namespace shimmer::metrics {

struct VideoGridOptions {
  std::vector<std::string> labels;  // one per test sequence, burnt into its tile
  bool with_reference = true;
  std::string reference_label = "reference";
  int width = 0, height = 0;  // of every input frame
  double fps = 30;
  int slow = 1;  // each frame is written this many times (slow motion)
};

// Where the parts of one tile lie in a grid frame.
struct GridTile {
  cv::Rect label, image, panel;  // panel: the error map, or the legend on the reference tile
};

// Tiles in rows of at most 3, each input frame enlarged by an integer factor
// (nearest neighbour) to at least kMinTileWidth pixels so labels stay
// legible; the frame is padded to even sizes for 4:2:0 encoders.
struct GridLayout {
  static constexpr int kMinTileWidth = 192;
  static constexpr int kLabelHeight = 22;
  int scale = 1;
  cv::Size frame;
  std::vector<GridTile> tiles;
};
GridLayout LayoutGrid(int tiles, int width, int height);

class VideoGrid {
 public:
  static constexpr int kMaxTiles = 9;  // the reference's (or the legend's) counts as one

  // Tries the H.264 fourcc (avc1) first, then MPEG-4 Part 2 (mp4v): whichever
  // the installed OpenCV/FFmpeg can encode. Written to a temporary name.
  static Result<std::unique_ptr<VideoGrid>> Open(const std::filesystem::path& file, VideoGridOptions options);
  ~VideoGrid();

  // One luminance frame (CV_32F) per test, in the order of the labels, and
  // the reference's (empty without one). Display only: tone-mapped with
  // x/(1+x) and sRGB-encoded; the metrics never see this. The error scale is
  // fixed by the first frame (the largest 99th percentile of |E| over the
  // tests) so that flicker shows as colour changing over time, not as a
  // rescaled image.
  Status AddFrame(const std::vector<cv::Mat>& tests, const cv::Mat& reference);

  // Closes the file and renames it into place.
  Status Finish();

  const GridLayout& layout() const { return layout_; }
  int frames_added() const { return frames_added_; }  // the MP4 has frames_added() * slow frames
  const char* fourcc_name() const { return fourcc_name_; }

 private:
  VideoGrid() = default;
  void DrawStatic();
  std::filesystem::path file_, temporary_;
  VideoGridOptions options_;
  GridLayout layout_;
  cv::VideoWriter writer_;
  cv::Mat frame_, background_;
  std::vector<cv::Mat> previous_;
  HeatmapRange range_;
  bool have_range_ = false;
  bool finished_ = false;
  int frames_added_ = 0;
  const char* fourcc_name_ = "";
};

// Sequences on disk into one grid video: every sequence opened (headers
// checked: one size, one length) before the file is, then read a frame at a
// time.
struct GridSequences {
  std::vector<std::filesystem::path> tests;
  std::vector<std::string> labels;  // empty: SequenceLabel of each test
  std::filesystem::path reference;  // empty: none
  SequenceRequest request;          // layer and fallback fps, as for the metrics
  int slow = 1;
};
struct GridVideoWritten {
  int tiles = 0, frames = 0;  // frames in the MP4 (input frames x slow)
  std::string fourcc;
};
Result<GridVideoWritten> WriteGridVideo(const GridSequences& sequences, const std::filesystem::path& file);

// What a sequence is called when nobody named it: its directory's name (a
// sequence.json: the name of the directory it is in).
std::string SequenceLabel(const std::filesystem::path& sequence);

// Tone-mapped (x/(1+x)), sRGB-encoded grey of a luminance frame: what a tile shows.
cv::Mat DisplayGrey(const cv::Mat& luminance);

}  // namespace shimmer::metrics
