// Glint "sparkle statistics" (docs/metrics.md, "Sparkle statistics"): how
// many pixels of the region are brighter than an absolute threshold in each
// frame, how much that count varies over time, and how long a bright pixel
// stays bright when followed along the motion vectors. Computed for the test
// sequence and the reference alike, so that a glint model's 1-spp frames can
// be compared with its supersampled reference (and a naive baseline).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

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
};

struct SparkleReport {
  double threshold = 0;  // tau, on linear luminance
  SparkleStatistics test;
  std::optional<SparkleStatistics> reference;  // with a reference
  // test / reference; empty without a reference or when either side is undefined or the denominator is 0.
  std::optional<double> mean_count_ratio, count_variance_ratio, lifetime_ratio;
};

// Follows one sequence's sparkles frame by frame: a pixel's age (frames it
// has been a sparkle, tracked through the motion vectors) in two int32
// planes, the previous frame's and the current one's. Rows of one frame are
// independent (each reads only the previous frame's ages), so AddRow may run
// for different rows on different threads; BeginFrame and EndFrame may not.
class SparkleTracker {
 public:
  SparkleTracker() = default;
  SparkleTracker(int width, int height, double threshold);

  bool active() const { return width_ > 0; }

  // Row y of the current frame: luminance (CV_32F row), the region row (0/1)
  // and the motion row (pixels towards the previous frame, (x, y) per pixel)
  // or null to track without warping (q = p).
  void AddRow(int y, const float* luminance, const uint8_t* region, const cv::Vec2f* motion);
  // After every row of the frame: adds up its counts and makes it the previous frame.
  void EndFrame();

  // The statistics over the frames so far (at least one).
  SparkleStatistics Statistics() const;

 private:
  struct RowCounts {
    long long sparkles = 0, births = 0, tracked = 0;
  };
  int width_ = 0, height_ = 0;
  double threshold_ = 0;
  int frame_ = 0;  // t of the frame being added
  std::vector<int32_t> previous_, current_;
  std::vector<RowCounts> rows_;
  std::vector<long long> counts_;
  long long births_ = 0, tracked_ = 0, later_sparkles_ = 0;
};

// The ratios of a report with both sides filled in.
void SetSparkleRatios(SparkleReport* report);

}  // namespace shimmer::metrics
