#include "shimmer/metrics/metrics_report.h"

#include <cmath>
#include <cstdio>
#include <optional>

#include <tbb/task_group.h>

#include "shimmer/core/host_memory.h"
#include "shimmer/metrics/metrics_accumulator.h"

namespace shimmer::metrics {

namespace {

constexpr int kDefaultSegmentLength = 64;

struct FramePair {
  LuminanceFrame test, reference;
};

std::string SizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

}  // namespace

Result<MetricsReport> ComputeMetrics(const MetricsOptions& options, const FrameObserver& observer) {
  using R = Result<MetricsReport>;
  if (!(options.sparkle_threshold >= 0) || !std::isfinite(options.sparkle_threshold)) {
    char given[32];
    std::snprintf(given, sizeof given, "%g", options.sparkle_threshold);
    return R::Failure(std::string("sparkle_threshold must be a finite number >= 0 (0: no sparkle statistics), got ") +
                      given);
  }
  auto test = OpenSequence(options.test, options.request);
  if (!test) return R::Failure(test.error());
  std::optional<ExrSequence> reference;
  MetricsReport report;
  report.warnings = test->warnings;
  if (options.reference) {
    // The reference is read in the layer chosen for the test, so that both
    // sides always measure the same quantity.
    SequenceRequest request = options.request;
    request.layer = test->layer;
    auto ref = OpenSequence(*options.reference, request);
    if (!ref) return R::Failure(ref.error());
    if (ref->width != test->width || ref->height != test->height)
      return R::Failure("TEST " + options.test.string() + " is " + SizeText(test->width, test->height) + " but REF " +
                        options.reference->string() + " is " + SizeText(ref->width, ref->height));
    if (ref->frames.size() != test->frames.size())
      return R::Failure("TEST " + options.test.string() + " has " + std::to_string(test->frames.size()) +
                        " frames but REF " + options.reference->string() + " has " +
                        std::to_string(ref->frames.size()));
    if (test->fps_source != "sequence.json" && ref->fps_source == "sequence.json") {
      test->fps = ref->fps;
      test->fps_source = "sequence.json";
    }
    reference = std::move(*ref);
  }
  const bool has_ref = reference.has_value();
  const int frames = static_cast<int>(test->frames.size());
  const int width = test->width, height = test->height;
  if (frames < 2)
    return R::Failure(options.test.string() + ": " + std::to_string(frames) +
                      " frame; temporal metrics need at least 2");

  const bool sparkles = options.sparkle_threshold > 0;
  // The reference's own motion vectors are read only for the sparkle lifetimes.
  const bool reference_motion = sparkles && has_ref && reference->has_motion;

  const FlickerSignal signal = options.signal.value_or(has_ref ? FlickerSignal::kError : FlickerSignal::kTest);
  if (signal == FlickerSignal::kError && !has_ref) return R::Failure("--signal error needs a reference sequence (REF)");
  const int segment_length =
      options.segment_length > 0 ? options.segment_length : std::min(frames, kDefaultSegmentLength);
  if (segment_length < 2 || segment_length > frames)
    return R::Failure("--segment " + std::to_string(segment_length) + " must be between 2 and the frame count (" +
                      std::to_string(frames) + ")");
  // What the pass holds per pixel: three pairs of moments and two difference
  // maps in double, the spectrum's L-frame ring in float, and two frame pairs
  // with motion being read and computed. Refused up front, with the numbers,
  // rather than found by the OOM killer on a huge sequence.
  // With a reference, the bootstrap's six float sums per frame block, the
  // first-frame shifts, and stderr.Y's two sums and its plane. With sparkle
  // statistics, two int32 age planes per sequence and the reference's motion.
  const int frame_blocks = (frames + FrameBlockLength(frames) - 1) / FrameBlockLength(frames);
  const double bytes_per_pixel = 3 * 16 + 2 * 8 + 4.0 * segment_length + 2 * (2 * 4 + 8) + 8 +
                                 (has_ref ? 24.0 * frame_blocks + 8 + 16 + 2 * 4 : 0.0) +
                                 (sparkles ? 8.0 * (has_ref ? 2 : 1) + (reference_motion ? 2 * 8 : 0) : 0.0);
  const double needed = bytes_per_pixel * double(width) * double(height);
  if (const double available = double(AvailableHostMemory()); available > 0 && needed > available) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "%s: measuring %dx%d frames needs about %.1f GiB of memory (with --segment %d); %.1f GiB are "
                  "available",
                  options.test.string().c_str(), width, height, needed / (1 << 30), segment_length,
                  available / (1 << 30));
    return R::Failure(text, ErrorCode::kOutOfMemory);
  }

  // The region M.
  cv::Mat region;
  if (options.mask_file) {
    auto mask = ReadMask(*options.mask_file, width, height);
    if (!mask) return R::Failure(mask.error());
    region = *mask;
    report.region = "mask:" + options.mask_file->string();
  } else if (options.highlight_mask) {
    auto mask = BuildHighlightMask(has_ref ? *reference : *test, options.highlight);
    if (!mask) return R::Failure(mask.error());
    region = *mask;
    report.region = "highlight";
    if (cv::countNonZero(region) == 0 && options.highlight.empty_falls_back_to_frame) {
      region = cv::Mat::ones(height, width, CV_8U);
      report.region = "frame (highlight mask empty)";
    }
  } else {
    region = cv::Mat::ones(height, width, CV_8U);
    report.region = "frame";
  }
  const long long region_pixels = cv::countNonZero(region);
  if (region_pixels == 0)
    return R::Failure(options.highlight_mask
                          ? "the highlight mask is empty: no pixel's specular luminance exceeds " +
                                std::to_string(options.highlight.threshold) + " (lower --highlight-threshold)"
                          : "the mask " + options.mask_file->string() + " has no nonzero pixel");

  AccumulatorSetup setup;
  setup.width = width;
  setup.height = height;
  setup.frames = frames;
  setup.fps = test->fps;
  setup.has_reference = has_ref;
  setup.with_motion = test->has_motion;
  setup.region = region;
  setup.signal = signal;
  setup.segment_length = segment_length;
  setup.reference_stderr = has_ref && reference->has_stderr;
  setup.sparkle_threshold = options.sparkle_threshold;
  MetricsAccumulator accumulator(setup);

  // The next frame pair is read (its chunks decoded in parallel) while this
  // one is computed. Both run as tasks of the one TBB pool that OpenCV's
  // parallel_for_ uses too: a separate reader thread would oversubscribe the
  // cores (measured 15 % slower on 2 cores than not overlapping at all).
  auto read = [&](int t) -> Result<FramePair> {
    FramePair pair;
    auto tf = ReadFrame(test->frames[t], test->layer, width, height, setup.with_motion);
    if (!tf) return tf.failure();
    pair.test = std::move(*tf);
    if (has_ref) {
      auto rf = ReadFrame(reference->frames[t], reference->layer, width, height, reference_motion,
                          setup.reference_stderr);
      if (!rf) return rf.failure();
      pair.reference = std::move(*rf);
    }
    return pair;
  };

  FramePair previous;
  Result<FramePair> current = read(0);
  for (int t = 0; t < frames; ++t) {
    if (!current) return current.failure();
    std::optional<Result<FramePair>> upcoming;
    tbb::task_group reading;
    // The read writes into `upcoming`; wait for it on every way out of this iteration.
    struct WaitOnExit {
      tbb::task_group& group;
      ~WaitOnExit() { group.wait(); }
    } wait_on_exit{reading};
    if (t + 1 < frames) reading.run([&, t] { upcoming = read(t + 1); });
    const cv::Mat& T = current->test.luminance;
    const cv::Mat& Rf = current->reference.luminance;
    accumulator.AddFrame(T, Rf, current->test.motion, test->frames[t].string(),
                         has_ref ? reference->frames[t].string() : std::string(), current->reference.stderr_y,
                         current->reference.motion);
    if (observer) {
      Status s =
          observer(ObservedFrame{t, test->fps, has_ref, T, has_ref ? Rf : (t > 0 ? previous.test.luminance : T)});
      if (!s) return s.failure();
    }
    reading.wait();
    previous = std::move(*current);
    if (upcoming) current = std::move(*upcoming);
  }

  report.test = options.test.string();
  if (has_ref) report.reference = options.reference->string();
  report.layer = test->layer;
  report.fps = test->fps;
  report.fps_source = test->fps_source;
  if (Status s = accumulator.Finish(&report); !s) return s.failure();
  return report;
}

nlohmann::json ToJson(const MetricsReport& r) {
  using nlohmann::json;
  auto optional = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  json j = {{"test", r.test},
            {"layer", r.layer},
            {"region", r.region},
            {"frames", r.frames},
            {"width", r.width},
            {"height", r.height},
            {"pixels", r.pixels},
            {"fps", r.fps},
            {"fps_source", r.fps_source},
            {"tv_test", r.tv_test},
            {"temporal_diff_test", r.temporal_diff_test},
            {"nan_pixels", r.nan_pixels},
            {"nan_samples", r.nan_samples}};
  if (!r.reference.empty()) {
    j["reference"] = r.reference;
    j["tv_ref"] = optional(r.tv_ref);
    j["tv_err"] = optional(r.tv_err);
    j["tv_ratio"] = optional(r.tv_ratio);
    j["energy_bias"] = optional(r.energy_bias);
    j["energy_bias_per_frame"] = r.energy_bias_per_frame;
    j["temporal_diff_err"] = optional(r.temporal_diff_err);
    j["rmse"] = optional(r.rmse);
    j["relmse"] = optional(r.relmse);
    j["relmse_temporal"] = optional(r.relmse_temporal);
    j["relmse_spatial"] = optional(r.relmse_spatial);
  }
  if (r.ci95) {
    auto interval = [](const std::optional<Interval>& i) { return i ? json::array({i->lo, i->hi}) : json(nullptr); };
    j["ci95"] = {{"tv_err", interval(r.ci95->tv_err)},
                 {"tv_ratio", interval(r.ci95->tv_ratio)},
                 {"energy_bias", interval(r.ci95->energy_bias)},
                 {"relmse", interval(r.ci95->relmse)},
                 {"relmse_temporal", interval(r.ci95->relmse_temporal)},
                 {"relmse_spatial", interval(r.ci95->relmse_spatial)},
                 {"flicker_index", interval(r.ci95->flicker_index)}};
  }
  if (r.bootstrap)
    j["bootstrap"] = {{"replicates", r.bootstrap->replicates},
                      {"frame_block", r.bootstrap->frame_block},
                      {"tile", r.bootstrap->tile},
                      {"seed", r.bootstrap->seed}};
  if (r.tv_err_floor) j["tv_err_floor"] = *r.tv_err_floor;
  if (r.ref_noise) j["ref_noise"] = *r.ref_noise;
  if (r.ref_mean) j["ref_mean"] = *r.ref_mean;
  if (r.relmse_noise_sigma) j["relmse_noise_sigma"] = *r.relmse_noise_sigma;
  if (r.warp_err) j["warp_err"] = *r.warp_err;
  if (r.sparkles) {
    const SparkleReport& s = *r.sparkles;
    auto statistics = [&](const SparkleStatistics& x) {
      return json{{"mean_count", x.mean_count},       {"count_variance", x.count_variance},
                  {"count_cv", optional(x.count_cv)}, {"mean_lifetime", optional(x.mean_lifetime)},
                  {"birth_rate", optional(x.birth_rate)}, {"motion", x.motion}};
    };
    json sparkles = {{"threshold", s.threshold}, {"test", statistics(s.test)}};
    if (s.reference) {
      sparkles["reference"] = statistics(*s.reference);
      sparkles["mean_count_ratio"] = optional(s.mean_count_ratio);
      sparkles["count_variance_ratio"] = optional(s.count_variance_ratio);
      sparkles["lifetime_ratio"] = optional(s.lifetime_ratio);
    }
    j["sparkles"] = std::move(sparkles);
  }
  j["flicker"] = {
      {"signal", r.flicker.signal},
      {"segment_length", r.flicker.segment_length},
      {"segments", r.flicker.segments},
      {"freq_hz", r.flicker.freq_hz},
      {"psd", r.flicker.psd},
      {"bands", {{"0-2Hz", r.flicker.band_low}, {"2-8Hz", r.flicker.band_mid}, {"8Hz-nyquist", r.flicker.band_high}}},
      {"flicker_index", r.flicker.flicker_index}};
  j["warnings"] = r.warnings;
  return j;
}

}  // namespace shimmer::metrics
