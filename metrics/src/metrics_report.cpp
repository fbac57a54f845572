#include "shimmer/metrics/metrics_report.h"

#include <cmath>
#include <optional>

#include <tbb/task_group.h>

#include "shimmer/metrics/energy_bias.h"
#include "shimmer/metrics/flicker_spectrum.h"
#include "shimmer/metrics/temporal_sensitivity.h"
#include "shimmer/metrics/temporal_variance.h"
#include "shimmer/metrics/warp_error.h"

namespace shimmer::metrics {

namespace {

// relMSE's denominator offset: keeps near-black reference pixels from
// dominating (the convention of the rendering literature's relMSE, e.g.
// Rousselle et al. 2011, with 0.01 as in DESIGN.md).
constexpr double kRelMseEpsilon = 0.01;
constexpr int kDefaultSegmentLength = 64;

struct FramePair {
  LuminanceFrame test, reference;
};

std::string SizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// Per-row partial sums of one frame: rows are the unit of parallel work, so
// summing them in row order afterwards keeps results independent of threading.
struct RowSums {
  double test = 0, reference = 0, error2 = 0, relative2 = 0;
  long long samples = 0, non_finite = 0;
};

double MeanOver(const cv::Mat& map, const cv::Mat& mask, long long count) {
  double sum = 0;
  for (int y = 0; y < map.rows; ++y) {
    const double* v = map.ptr<double>(y);
    const uint8_t* m = mask.ptr<uint8_t>(y);
    for (int x = 0; x < map.cols; ++x)
      if (m[x]) sum += v[x];
  }
  return count ? sum / count : 0.0;
}

cv::Mat MaskedFloat(const cv::Mat& map, const cv::Mat& mask) {
  cv::Mat out;
  map.convertTo(out, CV_32F);
  out.setTo(0, mask == 0);
  return out;
}

}  // namespace

Result<MetricsReport> ComputeMetrics(const MetricsOptions& options, const FrameObserver& observer) {
  using R = Result<MetricsReport>;
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

  const FlickerSignal signal = options.signal.value_or(has_ref ? FlickerSignal::kError : FlickerSignal::kTest);
  if (signal == FlickerSignal::kError && !has_ref)
    return R::Failure("--signal error needs a reference sequence (REF)");
  const int segment_length = options.segment_length > 0 ? options.segment_length
                                                        : std::min(frames, kDefaultSegmentLength);
  if (segment_length < 2 || segment_length > frames)
    return R::Failure("--segment " + std::to_string(segment_length) + " must be between 2 and the frame count (" +
                      std::to_string(frames) + ")");

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

  std::vector<int> region_indices;
  region_indices.reserve(region_pixels);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (region.at<uint8_t>(y, x)) region_indices.push_back(y * width + x);

  const bool with_motion = test->has_motion;
  TemporalMoments moments_test(width, height), moments_ref, moments_err;
  if (has_ref) moments_ref = TemporalMoments(width, height), moments_err = TemporalMoments(width, height);
  cv::Mat excluded = cv::Mat::zeros(height, width, CV_8U);  // sticky: a non-finite sample seen
  cv::Mat diff_test = cv::Mat::zeros(height, width, CV_64F), diff_err;
  if (has_ref) diff_err = cv::Mat::zeros(height, width, CV_64F);
  cv::Mat signal_frame = cv::Mat::zeros(height, width, CV_32F);
  FlickerSpectrum spectrum(region_indices, segment_length, test->fps);
  WarpError warp;
  std::vector<RowSums> rows(height);
  std::string first_non_finite;

  // The next frame pair is read (its chunks decoded in parallel) while this
  // one is computed. Both run as tasks of the one TBB pool that OpenCV's
  // parallel_for_ uses too: a separate reader thread would oversubscribe the
  // cores (measured 15 % slower on 2 cores than not overlapping at all).
  auto read = [&](int t) -> Result<FramePair> {
    FramePair pair;
    auto tf = ReadFrame(test->frames[t], test->layer, width, height, with_motion);
    if (!tf) return Result<FramePair>::Failure(tf.error());
    pair.test = std::move(*tf);
    if (has_ref) {
      auto rf = ReadFrame(reference->frames[t], reference->layer, width, height, false);
      if (!rf) return Result<FramePair>::Failure(rf.error());
      pair.reference = std::move(*rf);
    }
    return pair;
  };

  FramePair previous;
  Result<FramePair> current = read(0);
  for (int t = 0; t < frames; ++t) {
    if (!current) return R::Failure(current.error());
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

    cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& range) {
      for (int y = range.start; y < range.end; ++y) {
        const float* tv_row = T.ptr<float>(y);
        const float* rv_row = has_ref ? Rf.ptr<float>(y) : nullptr;
        const float* tp_row = t > 0 ? previous.test.luminance.ptr<float>(y) : nullptr;
        const float* rp_row = t > 0 && has_ref ? previous.reference.luminance.ptr<float>(y) : nullptr;
        const uint8_t* in = region.ptr<uint8_t>(y);
        uint8_t* bad = excluded.ptr<uint8_t>(y);
        float* sig = signal_frame.ptr<float>(y);
        double* dt = diff_test.ptr<double>(y);
        double* de = has_ref ? diff_err.ptr<double>(y) : nullptr;
        RowSums sums;
        for (int x = 0; x < width; ++x) {
          if (!in[x]) continue;
          const size_t i = static_cast<size_t>(y) * width + x;
          const double tv = tv_row[x], rv = has_ref ? rv_row[x] : 0.0;
          if (!std::isfinite(tv) || !std::isfinite(rv)) {
            // Excluded and counted, never propagated: one NaN would otherwise
            // turn every mean and the whole spectrum into NaN.
            ++sums.non_finite;
            bad[x] = 1;
            sig[x] = 0;
            continue;
          }
          const double e = tv - rv;
          sums.test += tv;
          sums.reference += rv;
          sums.error2 += e * e;
          sums.relative2 += e * e / (rv * rv + kRelMseEpsilon);
          ++sums.samples;
          if (bad[x]) {
            sig[x] = 0;
            continue;
          }
          moments_test.Add(i, tv);
          if (has_ref) {
            moments_ref.Add(i, rv);
            moments_err.Add(i, e);
          }
          if (tp_row) {
            dt[x] += std::abs(tv - tp_row[x]);
            if (has_ref) de[x] += std::abs(e - (static_cast<double>(tp_row[x]) - rp_row[x]));
          }
          sig[x] = static_cast<float>(signal == FlickerSignal::kError ? e : tv);
        }
        rows[y] = sums;
      }
    });

    RowSums frame_sums;
    for (const RowSums& r : rows) {
      frame_sums.test += r.test;
      frame_sums.reference += r.reference;
      frame_sums.error2 += r.error2;
      frame_sums.relative2 += r.relative2;
      frame_sums.samples += r.samples;
      frame_sums.non_finite += r.non_finite;
    }
    if (frame_sums.non_finite > 0) {
      report.nan_samples += frame_sums.non_finite;
      if (first_non_finite.empty())
        first_non_finite = !cv::checkRange(T) || !has_ref ? test->frames[t].string() : reference->frames[t].string();
    }
    if (has_ref && frame_sums.samples > 0) {
      if (auto bias = RelativeBias(frame_sums.test, frame_sums.reference)) report.energy_bias_per_frame.push_back(*bias);
      report.rmse_per_frame.push_back(std::sqrt(frame_sums.error2 / frame_sums.samples));
      // relMSE is averaged the same way: per frame, then over frames.
      report.relmse = report.relmse.value_or(0.0) + frame_sums.relative2 / frame_sums.samples;
    }

    spectrum.AddFrame(signal_frame, excluded);
    if (with_motion && t > 0)
      warp.AddFrame(previous.test.luminance, T, current->test.motion, region, excluded);
    if (observer) {
      Status s = observer(ObservedFrame{t, test->fps, has_ref, T, has_ref ? Rf : (t > 0 ? previous.test.luminance : T)});
      if (!s) return R::Failure(s.error());
    }
    reading.wait();
    previous = std::move(*current);
    if (upcoming) current = std::move(*upcoming);
  }

  // Pixels with any non-finite sample leave the region for every per-pixel
  // metric, so that all of them describe the same set of pixels.
  cv::Mat good = (region != 0) & (excluded == 0);
  good /= 255;
  const long long used = cv::countNonZero(good);
  report.nan_pixels = region_pixels - used;
  if (used == 0)
    return R::Failure("every pixel of the region has NaN or Inf values (first in " + first_non_finite + ")");
  if (report.nan_pixels > 0)
    report.warnings.push_back(std::to_string(report.nan_pixels) + " pixel(s) have NaN/Inf values (" +
                              std::to_string(report.nan_samples) + " samples, first in " + first_non_finite +
                              "); excluded from the metrics");

  report.test = options.test.string();
  if (has_ref) report.reference = options.reference->string();
  report.layer = test->layer;
  report.frames = frames;
  report.width = width;
  report.height = height;
  report.pixels = region_pixels;
  report.fps = test->fps;
  report.fps_source = test->fps_source;
  report.region_mask = good;

  cv::Mat var_test = moments_test.VarianceMap();
  report.tv_test = MeanOver(var_test, good, used);
  report.tv_test_map = MaskedFloat(var_test, good);
  report.temporal_diff_test = MeanOver(diff_test, good, used) / (frames - 1);
  if (has_ref) {
    cv::Mat var_ref = moments_ref.VarianceMap(), var_err = moments_err.VarianceMap();
    report.tv_ref = MeanOver(var_ref, good, used);
    report.tv_err = MeanOver(var_err, good, used);
    report.tv_ref_map = MaskedFloat(var_ref, good);
    report.tv_err_map = MaskedFloat(var_err, good);
    if (*report.tv_ref > 0) report.tv_ratio = report.tv_test / *report.tv_ref;
    cv::Mat mean_test = moments_test.MeanMap(), mean_ref = moments_ref.MeanMap();
    // Every good pixel has all N samples, so sum_t = N * mean_t.
    report.energy_bias = RelativeBias(MeanOver(mean_test, good, 1) * frames, MeanOver(mean_ref, good, 1) * frames);
    report.energy_bias_map = EnergyBiasMap(mean_test, mean_ref, good, cv::Mat());
    report.temporal_diff_err = MeanOver(diff_err, good, used) / (frames - 1);
    double rmse = 0;
    for (double r : report.rmse_per_frame) rmse += r;
    if (!report.rmse_per_frame.empty()) {
      report.rmse = rmse / report.rmse_per_frame.size();
      report.relmse = *report.relmse / report.rmse_per_frame.size();
    }
    if (!report.tv_ratio) report.warnings.push_back("tv_ratio is undefined: the reference has zero temporal variance");
    if (!report.energy_bias) report.warnings.push_back("energy_bias is undefined: the reference sums to zero");
  }
  if (with_motion && !warp.empty()) report.warp_err = warp.mean();

  FlickerResult& f = report.flicker;
  f.signal = signal == FlickerSignal::kError ? "error" : "test";
  f.segment_length = segment_length;
  f.segments = spectrum.segments();
  f.freq_hz = spectrum.Frequencies();
  f.psd = spectrum.Psd();
  BandPowers bands = IntegrateBands(f.freq_hz, f.psd);
  f.band_low = bands.low;
  f.band_mid = bands.mid;
  f.band_high = bands.high;
  f.flicker_index = FlickerIndex(f.freq_hz, f.psd);
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
  }
  if (r.warp_err) j["warp_err"] = *r.warp_err;
  j["flicker"] = {{"signal", r.flicker.signal},
                  {"segment_length", r.flicker.segment_length},
                  {"segments", r.flicker.segments},
                  {"freq_hz", r.flicker.freq_hz},
                  {"psd", r.flicker.psd},
                  {"bands", {{"0-2Hz", r.flicker.band_low}, {"2-8Hz", r.flicker.band_mid},
                             {"8Hz-nyquist", r.flicker.band_high}}},
                  {"flicker_index", r.flicker.flicker_index}};
  j["warnings"] = r.warnings;
  return j;
}

}  // namespace shimmer::metrics
