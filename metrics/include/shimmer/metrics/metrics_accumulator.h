// The metrics of docs/metrics.md accumulated frame by frame: per-pixel
// temporal moments, frame differences, per-frame energy and error sums, the
// spectrum's L-frame ring and the warp error. Frames come from anywhere: EXR
// sequences (ComputeMetrics), or a renderer's frames in memory.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "shimmer/core/result.h"
#include "shimmer/metrics/flicker_spectrum.h"
#include "shimmer/metrics/metrics_report.h"
#include "shimmer/metrics/sparkle_statistics.h"
#include "shimmer/metrics/temporal_variance.h"
#include "shimmer/metrics/warp_error.h"

namespace shimmer::metrics {

namespace detail {
struct PixelRowTerms;
}

struct AccumulatorSetup {
  int width = 0, height = 0;
  int frames = 0;  // how many AddFrame calls will come (the spectrum's segments depend on it)
  double fps = 0;
  bool has_reference = false;
  bool with_motion = false;  // the test frames carry motion vectors (warp error)
  cv::Mat region;            // CV_8U 0/1: the pixels measured
  FlickerSignal signal = FlickerSignal::kTest;
  int segment_length = 0;         // Welch segment, 2..frames
  bool reference_stderr = false;  // every reference frame comes with stderr.Y
  BootstrapSettings bootstrap;
  // > 0: sparkle statistics with this contrast to a pixel's neighbourhood
  // (docs/metrics.md, "Sparkle statistics"); 0 leaves them out at no cost.
  double sparkle_threshold = 0;
};

class MetricsAccumulator {
 public:
  explicit MetricsAccumulator(const AccumulatorSetup& setup);

  // Frame t, in order: luminance planes (CV_32F), `reference` empty without a
  // reference, `motion` (CV_32FC2) empty without motion. The sources name the
  // frames in the warning about the first NaN or Inf. `reference_stderr`
  // (CV_32F): the reference's per-pixel standard error, with
  // setup.reference_stderr. `reference_motion` (CV_32FC2, may be empty): the
  // reference's own motion vectors, read only for the sparkle lifetimes; each
  // side's sparkles are tracked through its own motion, else the other's.
  void AddFrame(const cv::Mat& test, const cv::Mat& reference, const cv::Mat& motion, const std::string& test_source,
                const std::string& reference_source = {}, const cv::Mat& reference_stderr = cv::Mat(),
                const cv::Mat& reference_motion = cv::Mat());

  // Writes every metric, map and flicker result into `report`, and its
  // warnings; fails when every pixel of the region had a non-finite sample.
  Status Finish(MetricsReport* report);

 private:
  AccumulatorSetup setup_;
  std::vector<int> region_indices_;
  long long region_pixels_ = 0;
  TemporalMoments moments_test_, moments_ref_, moments_err_;
  cv::Mat excluded_;  // sticky: a non-finite sample seen
  cv::Mat diff_test_, diff_err_;
  cv::Mat signal_frame_;
  FlickerSpectrum spectrum_;
  WarpError warp_;
  cv::Mat previous_test_, previous_ref_;
  int frames_added_ = 0;
  long long nan_samples_ = 0;
  std::string first_non_finite_;
  std::vector<double> energy_bias_per_frame_, rmse_per_frame_;
  double relmse_sum_ = 0;

  // Whose motion vectors each side's sparkles follow this frame.
  struct SparkleTracks {
    const cv::Mat* test = nullptr;
    const cv::Mat* reference = nullptr;
  };
  SparkleTracks TracksOf(const cv::Mat& motion, const cv::Mat& reference_motion);
  void AddCellRow(int y, const float* test_row, const float* reference_row, const float* stderr_row,
                  const detail::PixelRowTerms& terms, float* block_cells, int block, std::vector<double>& tile_squares,
                  std::vector<uint8_t>& tile_any);

  // The bootstrap's sums (with a reference): per (block, region pixel),
  // block-major, a pixel's first moments (kPixelSums floats); per (tile,
  // block), tile-major, the sums that enter a tile linearly (kSquareSums
  // doubles, kind-major within a tile). Nine floats per pixel and block
  // were a quarter of a 1080p pass's memory.
  void AddIntervals(MetricsReport* report, const cv::Mat& good, double reference_sum) const;
  std::vector<int> region_index_;  // row-major pixel -> index in region_indices_, -1 outside
  int block_length_ = 0;
  std::vector<int> block_frames_;
  HugePageVector<float> cells_;
  HugePageVector<double> squares_;
  int tiles_x_ = 0;
  std::vector<float> shifts_;  // (t0, r0) per region pixel
  // Per region pixel, in double: sum_t w, sum_t w E, sum_t w E^2 with
  // w = 1 / (R^2 + eps), for relmse's temporal/spatial split.
  HugePageVector<double> joint_;
  // Per region pixel, with stderr.Y: sum_t s^2, sum_t (d relmse term / dR)^2 s^2,
  // and sum_t w s^2 (what the noise adds to relmse's temporal part).
  HugePageVector<double> noise_, relmse_noise_, weighted_noise_;
  int stderr_frames_ = 0;

  // Sparkle statistics (setup.sparkle_threshold > 0): one tracker per
  // sequence, and whose motion vectors each followed ("test", "reference",
  // "none"), as of frame 1.
  SparkleTracker sparkle_test_, sparkle_ref_;
  std::string sparkle_motion_test_ = "none", sparkle_motion_ref_ = "none";
};

}  // namespace shimmer::metrics
