#include "shimmer/metrics/metrics_report.h"

#include <array>
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

namespace {

// The test sequence and, with options.reference, the reference, checked to
// match in size and frame count.
struct OpenedSequences {
  ExrSequence test;
  std::optional<ExrSequence> reference;
};

Result<OpenedSequences> OpenSequences(const MetricsOptions& options) {
  using R = Result<OpenedSequences>;
  auto test = OpenSequence(options.test, options.request);
  if (!test) return R::Failure(test.error());
  OpenedSequences opened{std::move(*test), std::nullopt};
  ExrSequence& t = opened.test;
  if (options.reference) {
    // The reference is read in the layer chosen for the test, so that both
    // sides always measure the same quantity.
    SequenceRequest request = options.request;
    request.layer = t.layer;
    auto ref = OpenSequence(*options.reference, request);
    if (!ref) return R::Failure(ref.error());
    if (ref->width != t.width || ref->height != t.height)
      return R::Failure("TEST " + options.test.string() + " is " + SizeText(t.width, t.height) + " but REF " +
                        options.reference->string() + " is " + SizeText(ref->width, ref->height));
    if (ref->frames.size() != t.frames.size())
      return R::Failure("TEST " + options.test.string() + " has " + std::to_string(t.frames.size()) +
                        " frames but REF " + options.reference->string() + " has " +
                        std::to_string(ref->frames.size()));
    if (t.fps_source != "sequence.json" && ref->fps_source == "sequence.json") {
      t.fps = ref->fps;
      t.fps_source = "sequence.json";
    }
    opened.reference = std::move(*ref);
  }
  const int frames = static_cast<int>(t.frames.size());
  if (frames < 2)
    return R::Failure(options.test.string() + ": " + std::to_string(frames) +
                      " frame; temporal metrics need at least 2");
  return opened;
}

// What the pass holds per pixel: three pairs of moments and two difference
// maps in double, the spectrum's L-frame ring in float, and two frame pairs
// with motion being read and computed. Refused up front, with the numbers,
// rather than found by the OOM killer on a huge sequence.
// With a reference, the bootstrap's six float sums per frame block, the
// first-frame shifts, and stderr.Y's two sums and its plane. With sparkle
// statistics, two int32 age planes per sequence and the reference's motion.
Status CheckMemory(const MetricsOptions& options, const AccumulatorSetup& setup, bool reference_motion) {
  const bool has_ref = setup.has_reference, sparkles = setup.sparkle_threshold > 0;
  const int frame_blocks = (setup.frames + FrameBlockLength(setup.frames) - 1) / FrameBlockLength(setup.frames);
  const double bytes_per_pixel = 3 * 16 + 2 * 8 + 4.0 * setup.segment_length + 2 * (2 * 4 + 8) + 8 +
                                 (has_ref ? 24.0 * frame_blocks + 8 + 16 + 2 * 4 : 0.0) +
                                 (sparkles ? 8.0 * (has_ref ? 2 : 1) + (reference_motion ? 2 * 8 : 0) : 0.0);
  const double needed = bytes_per_pixel * double(setup.width) * double(setup.height);
  if (const double available = double(AvailableHostMemory()); available > 0 && needed > available) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "%s: measuring %dx%d frames needs about %.1f GiB of memory (with --segment %d); %.1f GiB are "
                  "available",
                  options.test.string().c_str(), setup.width, setup.height, needed / (1 << 30),
                  setup.segment_length, available / (1 << 30));
    return Status::Failure(text, ErrorCode::kOutOfMemory);
  }
  return Ok();
}

// The region M: the mask file, the highlight mask or the whole frame; its
// name goes into report->region.
Result<cv::Mat> MeasuredRegion(const MetricsOptions& options, const OpenedSequences& seq, MetricsReport* report) {
  using R = Result<cv::Mat>;
  const int width = seq.test.width, height = seq.test.height;
  cv::Mat region;
  if (options.mask_file) {
    auto mask = ReadMask(*options.mask_file, width, height);
    if (!mask) return R::Failure(mask.error());
    region = *mask;
    report->region = "mask:" + options.mask_file->string();
  } else if (options.highlight_mask) {
    auto mask = BuildHighlightMask(seq.reference ? *seq.reference : seq.test, options.highlight);
    if (!mask) return R::Failure(mask.error());
    region = *mask;
    report->region = "highlight";
    if (cv::countNonZero(region) == 0 && options.highlight.empty_falls_back_to_frame) {
      region = cv::Mat::ones(height, width, CV_8U);
      report->region = "frame (highlight mask empty)";
    }
  } else {
    region = cv::Mat::ones(height, width, CV_8U);
    report->region = "frame";
  }
  if (cv::countNonZero(region) == 0)
    return R::Failure(options.highlight_mask
                          ? "the highlight mask is empty: no pixel's specular luminance exceeds " +
                                std::to_string(options.highlight.threshold) + " (lower --highlight-threshold)"
                          : "the mask " + options.mask_file->string() + " has no nonzero pixel");
  return region;
}

// Every frame pair into the accumulator, in order. The next pair is read
// (its chunks decoded in parallel) while this one is computed. Both run as
// tasks of the one TBB pool that OpenCV's parallel_for_ uses too: a separate
// reader thread would oversubscribe the cores (measured 15 % slower on 2
// cores than not overlapping at all). Pairs are read into a ring of three
// whose planes are reused: frame t is computed while t + 1 is read, and the
// observer may still be shown t - 1.
Status AccumulateFrames(const OpenedSequences& seq, const AccumulatorSetup& setup, bool reference_motion,
                        const FrameObserver& observer, MetricsAccumulator* accumulator) {
  const ExrSequence& test = seq.test;
  const bool has_ref = setup.has_reference;
  const int frames = setup.frames, width = setup.width, height = setup.height;
  FrameScratch scratch;  // only the reading task uses it, one read at a time
  std::array<FramePair, 3> ring;
  auto read = [&](int t) -> Status {
    FramePair& pair = ring[t % 3];
    if (Status s = ReadFrameInto(test.frames[t], test.layer, width, height, setup.with_motion, false, scratch,
                                 pair.test);
        !s)
      return s;
    if (!has_ref) return Ok();
    return ReadFrameInto(seq.reference->frames[t], seq.reference->layer, width, height, reference_motion,
                         setup.reference_stderr, scratch, pair.reference);
  };

  Status current = read(0);
  for (int t = 0; t < frames; ++t) {
    if (!current) return current;
    Status upcoming = Ok();
    tbb::task_group reading;
    // The read writes into `upcoming`; wait for it on every way out of this iteration.
    struct WaitOnExit {
      tbb::task_group& group;
      ~WaitOnExit() { group.wait(); }
    } wait_on_exit{reading};
    if (t + 1 < frames) reading.run([&, t] { upcoming = read(t + 1); });
    const FramePair& pair = ring[t % 3];
    const cv::Mat& T = pair.test.luminance;
    const cv::Mat& Rf = pair.reference.luminance;
    accumulator->AddFrame(T, Rf, pair.test.motion, test.frames[t].string(),
                          has_ref ? seq.reference->frames[t].string() : std::string(), pair.reference.stderr_y,
                          pair.reference.motion);
    if (observer) {
      const cv::Mat& previous = t > 0 ? ring[(t + 2) % 3].test.luminance : T;
      Status s = observer(ObservedFrame{t, test.fps, has_ref, T, has_ref ? Rf : previous});
      if (!s) return s;
    }
    reading.wait();
    current = std::move(upcoming);
  }
  return Ok();
}

}  // namespace

Result<MetricsReport> ComputeMetrics(const MetricsOptions& options, const FrameObserver& observer) {
  using R = Result<MetricsReport>;
  if (!(options.sparkle_threshold >= 0) || !std::isfinite(options.sparkle_threshold)) {
    char given[32];
    std::snprintf(given, sizeof given, "%g", options.sparkle_threshold);
    return R::Failure(std::string("sparkle_threshold must be a finite number >= 0 (0: no sparkle statistics), got ") +
                      given);
  }
  auto seq = OpenSequences(options);
  if (!seq) return R::Failure(seq.error());
  const ExrSequence& test = seq->test;
  const bool has_ref = seq->reference.has_value();
  const int frames = static_cast<int>(test.frames.size());
  MetricsReport report;
  report.warnings = test.warnings;

  const FlickerSignal signal = options.signal.value_or(has_ref ? FlickerSignal::kError : FlickerSignal::kTest);
  if (signal == FlickerSignal::kError && !has_ref) return R::Failure("--signal error needs a reference sequence (REF)");
  const int segment_length =
      options.segment_length > 0 ? options.segment_length : std::min(frames, kDefaultSegmentLength);
  if (segment_length < 2 || segment_length > frames)
    return R::Failure("--segment " + std::to_string(segment_length) + " must be between 2 and the frame count (" +
                      std::to_string(frames) + ")");

  AccumulatorSetup setup;
  setup.width = test.width;
  setup.height = test.height;
  setup.frames = frames;
  setup.fps = test.fps;
  setup.has_reference = has_ref;
  setup.with_motion = test.has_motion;
  setup.signal = signal;
  setup.segment_length = segment_length;
  setup.reference_stderr = has_ref && seq->reference->has_stderr;
  setup.sparkle_threshold = options.sparkle_threshold;
  // The reference's own motion vectors are read only for the sparkle lifetimes.
  const bool reference_motion = setup.sparkle_threshold > 0 && has_ref && seq->reference->has_motion;
  if (Status s = CheckMemory(options, setup, reference_motion); !s) return s.failure();
  auto region = MeasuredRegion(options, *seq, &report);
  if (!region) return region.failure();
  setup.region = *region;

  MetricsAccumulator accumulator(setup);
  if (Status s = AccumulateFrames(*seq, setup, reference_motion, observer, &accumulator); !s) return s.failure();
  report.test = options.test.string();
  if (has_ref) report.reference = options.reference->string();
  report.layer = test.layer;
  report.fps = test.fps;
  report.fps_source = test.fps_source;
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
      auto interval = [](const std::optional<Interval>& i) { return i ? json::array({i->lo, i->hi}) : json(nullptr); };
      sparkles["ci95"] = {{"mean_count_ratio", interval(s.mean_count_ratio_ci)},
                          {"count_variance_ratio", interval(s.count_variance_ratio_ci)},
                          {"lifetime_ratio", interval(s.lifetime_ratio_ci)}};
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
