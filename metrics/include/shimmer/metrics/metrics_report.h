// All metrics of docs/metrics.md in one streaming pass over a test
// sequence and an optional reference: one frame of each resident (plus the
// previous one for differences), the spectrum's L-frame ring, per-pixel
// accumulators; EXR reading of frame t+1 overlaps the computing of frame t.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "shimmer/core/result.h"
#include "shimmer/metrics/block_bootstrap.h"
#include "shimmer/metrics/exr_sequence.h"
#include "shimmer/metrics/highlight_mask.h"
#include "shimmer/metrics/sparkle_statistics.h"

namespace shimmer::metrics {

enum class FlickerSignal { kError, kTest };

struct MetricsOptions {
  std::filesystem::path test;
  std::optional<std::filesystem::path> reference;
  SequenceRequest request;  // --layer, --fps
  std::optional<std::filesystem::path> mask_file;
  bool highlight_mask = false;
  HighlightMaskOptions highlight;
  std::optional<FlickerSignal> signal;  // default: error with a reference, else test
  int segment_length = 0;               // 0: min(N, 64)
  // > 0: sparkle statistics with this contrast: a pixel above this many times
  // its neighbourhood's mean luminance is a sparkle (docs/metrics.md, "Sparkle
  // statistics"); 0: none (and nothing of them in the report or its JSON).
  double sparkle_threshold = 0;
};

// What an observer sees of each frame, in order, as read (luminance).
struct ObservedFrame {
  int index = 0;
  double fps = 0;
  bool has_reference = false;
  const cv::Mat& test;
  const cv::Mat& other;  // R_t with a reference, else T_{t-1} (T_0 for t = 0)
};
using FrameObserver = std::function<Status(const ObservedFrame&)>;

struct FlickerResult {
  std::string signal;  // "error" or "test"
  int segment_length = 0;
  int segments = 0;
  std::vector<double> freq_hz, psd;
  double band_low = 0, band_mid = 0, band_high = 0;
  double flicker_index = 0;
};

struct MetricsReport {
  std::string test, reference;  // as given
  std::string layer, region;    // region: "frame", "mask:<file>" or "highlight"
  int frames = 0, width = 0, height = 0;
  long long pixels = 0;  // in the region
  double fps = 0;
  std::string fps_source;

  double tv_test = 0;
  std::optional<double> tv_ref, tv_err, tv_ratio, energy_bias, temporal_diff_err, rmse, relmse;
  // relmse, the joint error, split (docs/metrics.md, "Joint error"): the
  // temporal part (each pixel's weighted variance of E about its weighted
  // temporal mean) and the spatial part (that mean's error); they add up to relmse.
  std::optional<double> relmse_temporal, relmse_spatial;
  std::vector<double> energy_bias_per_frame, rmse_per_frame;  // with a reference
  double temporal_diff_test = 0;                              // mean over t >= 1 and M of |T_t - T_{t-1}|
  std::optional<double> warp_err;                             // when the test frames carry motion.X/Y
  long long nan_pixels = 0;                                   // region pixels with a non-finite sample anywhere
  long long nan_samples = 0;                                  // (pixel, frame) samples that were non-finite
  FlickerResult flicker;

  // With a reference: 95 % intervals (docs/metrics.md, "Intervals"), a
  // metric's absent when the metric is undefined; how they were drawn.
  struct Bootstrap {
    int replicates = 0, frame_block = 0, tile = 0;
    std::uint64_t seed = 0;
  };
  std::optional<TileBlockStatistics::Intervals> ci95;
  std::optional<Bootstrap> bootstrap;
  // With a reference carrying stderr.Y: mean over M and t of stderr.Y^2 over
  // tv_err, in [0, 1]: the share of tv_err the reference's own noise explains.
  std::optional<double> tv_err_floor;
  // F itself (luminance², the variance the reference's noise adds), and the
  // reference's mean luminance over M and t: sqrt(F) / ref_mean is the
  // reference noise's contrast, what the decision rule compares with the
  // smallest visible flicker (experiments/report/decision_rule.h).
  std::optional<double> ref_noise;
  std::optional<double> ref_mean;
  // The standard deviation the reference's noise adds to relmse (the delta
  // method's sigma that widens its interval): a paired relmse difference is
  // widened by the two rows' sum.
  std::optional<double> relmse_noise_sigma;
  // With MetricsOptions::sparkle_threshold > 0.
  std::optional<SparkleReport> sparkles;

  // Per-pixel maps (CV_32F), 0 outside the region and at excluded pixels.
  cv::Mat region_mask;  // CV_8U 0/1, after exclusion of non-finite pixels
  cv::Mat tv_test_map, tv_ref_map, tv_err_map, energy_bias_map;
  std::vector<std::string> warnings;
};

Result<MetricsReport> ComputeMetrics(const MetricsOptions& options, const FrameObserver& observer = {});

// The --json object; reference-relative keys only with a reference.
nlohmann::json ToJson(const MetricsReport& report);

}  // namespace shimmer::metrics
