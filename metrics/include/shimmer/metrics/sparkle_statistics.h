// Glint "sparkle statistics" (docs/metrics.md, "Sparkle statistics"): how
// many pixels of the region stand out of their neighbourhood by a contrast
// in each frame, how much that count varies over time, and how long such a
// pixel stays one when followed along the motion vectors. Computed for the
// test sequence and the reference alike, so that a glint model's 1-spp
// frames can be compared with its supersampled reference (and a naive
// baseline).
//
// A sparkle is a pixel whose luminance is above `contrast` times the mean
// luminance of its neighbourhood in the same frame (a Gaussian window of
// kSparkleNeighbourhoodSigma pixels over the region's finite pixels, the
// pixel itself left out), and that mean is held to at least
// kSparkleFloorShare of the region's mean: the neighbourhood's mean is what
// a glint-free surface (the smooth NDF D_g) would show there, so the count
// measures the glitter's contrast, not the exposure or the shading level
// (scaling a frame's luminance leaves it unchanged). The floor keeps a
// speck on a black background from counting as a sparkle of infinite
// contrast.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "shimmer/metrics/block_bootstrap.h"

namespace shimmer::metrics {

// One sequence's statistics. Undefined values (a zero denominator) are empty.
struct SparkleStatistics {
  double mean_count = 0;                // 1/N sum_t count_t
  double count_variance = 0;            // 1/N sum_t (count_t - mean_count)^2 (population variance)
  std::optional<double> count_cv;       // sqrt(count_variance) / mean_count
  std::optional<double> mean_lifetime;  // frames: uncensored sparkle pixel-frames / births (t >= 1)
  std::optional<double> birth_rate;     // births / sparkle pixel-frames, both over t >= 1
  std::string motion;                   // whose motion vectors tracked it: "test", "reference" or "none"
  // The raw sums the above come from.
  std::vector<long long> counts;  // count_t, t = 0..N-1
  long long births = 0;           // sparkle pixels with age 1 at t >= 1
  long long tracked = 0;          // sparkle pixel-frames whose track starts after frame 0 (age <= t)
  // The same three per tile and frame, for the intervals: the tiles are
  // the square tiles that hold region pixels, in row order, and entry
  // [t * tiles + i] is tile i in frame t.
  int tiles = 0;
  std::vector<int> tile_sparkles, tile_births, tile_tracked;
};

// The neighbourhood's Gaussian sigma, in pixels: wide enough that the
// window holds many glints (its effective area, 4 pi sigma^2, is about 110
// pixels), narrow enough to follow a highlight's shading across a 96-pixel
// frame.
inline constexpr double kSparkleNeighbourhoodSigma = 3.0;
// The floor of the neighbourhood's mean, as a share of the region's mean
// luminance in that frame.
inline constexpr double kSparkleFloorShare = 0.05;

struct SparkleReport {
  double threshold = 0;  // the contrast: a sparkle is above threshold x its neighbourhood's mean
  SparkleStatistics test;
  std::optional<SparkleStatistics> reference;  // with a reference
  // test / reference; empty without a reference or when either side is undefined or the denominator is 0.
  std::optional<double> mean_count_ratio, count_variance_ratio, lifetime_ratio;
  // Their 95 % intervals (SetSparkleIntervals); empty where the ratio is.
  std::optional<Interval> mean_count_ratio_ci, count_variance_ratio_ci, lifetime_ratio_ci;
};

// Follows one sequence's sparkles frame by frame: a pixel's age (frames it
// has been a sparkle, tracked through the motion vectors) in two int32
// planes, the previous frame's and the current one's. AddRow records a row
// of the current frame and may run for different rows on different threads;
// EndFrame, which needs the whole frame for the neighbourhoods, finds and
// tracks the sparkles, and may not. AddRow copies the luminance and region
// rows but keeps the motion row's pointer: it must live until EndFrame returns.
class SparkleTracker {
 public:
  SparkleTracker() = default;
  // `tile`: the side of the square tiles the intervals resample.
  SparkleTracker(int width, int height, double contrast, int tile);

  bool active() const { return width_ > 0; }

  // Row y of the current frame: luminance (CV_32F row), the region row (0/1)
  // and the motion row (pixels towards the previous frame, (x, y) per pixel)
  // or null to track without warping (q = p).
  void AddRow(int y, const float* luminance, const uint8_t* region, const cv::Vec2f* motion);
  // After every row of the frame: finds its sparkles, tracks them, adds up
  // its counts and makes it the previous frame.
  void EndFrame();

  // The statistics over the frames so far (at least one).
  SparkleStatistics Statistics() const;

 private:
  struct RowCounts {
    long long sparkles = 0, births = 0, tracked = 0;
    std::vector<int> per_tile;  // sparkles, births, tracked of each tile column in this row
  };
  // Row y's sparkles and their ages (frame t's `current_`).
  RowCounts TrackRow(int y, const uint8_t* sparkle, const cv::Vec2f* motion);

  int width_ = 0, height_ = 0;
  double contrast_ = 0;
  int tile_ = 8, tiles_x_ = 0, tiles_y_ = 0;
  std::vector<uint8_t> tile_in_region_;                   // per tile of the frame: ever held a region pixel
  std::vector<int> tile_sparkles_, tile_births_, tile_tracked_;  // [frame][every tile of the frame]
  cv::Mat luminance_, region_;                    // the current frame's rows (CV_32F, CV_8U)
  std::vector<const cv::Vec2f*> motion_rows_;     // its motion rows, or nulls
  int frame_ = 0;  // t of the frame being added
  std::vector<int32_t> previous_, current_;
  std::vector<RowCounts> rows_;
  std::vector<long long> counts_;
  long long births_ = 0, tracked_ = 0, later_sparkles_ = 0;
};

// The ratios of a report with both sides filled in.
void SetSparkleRatios(SparkleReport* report);

// The ratios' 95 % intervals, by the block bootstrap of the other metrics
// (block_bootstrap.h): tiles and frame blocks resampled together, the test
// and the reference with the same draws (so a ratio's interval holds what
// the two sides do not share), and the interaction corrected as there. A
// ratio left empty by SetSparkleRatios keeps no interval; so do all of them
// with fewer than 2 frames or sides of other sizes.
void SetSparkleIntervals(SparkleReport* report, const std::vector<int>& block_frames,
                         const BootstrapSettings& settings);

}  // namespace shimmer::metrics
