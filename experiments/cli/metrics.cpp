// `shimmer metrics TEST [REF]`: the temporal metrics of docs/metrics.md on any EXR
// sequence, from shimmer's renderer or from anyone else's.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "commands.h"
#include "shimmer/metrics/metrics_report.h"
#include "shimmer/metrics/report_files.h"
#include "shimmer/metrics/video_grid.h"

namespace shimmer::cli {

namespace {

namespace m = shimmer::metrics;

struct MetricsCliOptions {
  std::string test, reference;
  double fps = 0;
  std::string layer, mask, signal, out, video;
  int slow = 1;
  bool highlight_mask = false;
  double highlight_threshold = m::HighlightMaskOptions{}.threshold;
  int highlight_dilate = m::HighlightMaskOptions{}.dilate_radius;
  int segment = 0;
  double sparkle_threshold = 0;  // 0: no sparkle statistics
  bool json = false;
};

void Warn(const std::string& text) { std::fprintf(stderr, "shimmer: warning: %s\n", text.c_str()); }

void PrintOptional(const char* name, const std::optional<double>& v) {
  if (v)
    std::printf("%-18s %.6g\n", name, *v);
  else
    std::printf("%-18s undefined\n", name);
}

// A value and, when there is one, its 95 % interval beside it.
void PrintWithInterval(const char* name, const std::optional<double>& v, const std::optional<m::Interval>& ci) {
  if (!v) {
    std::printf("%-18s undefined\n", name);
    return;
  }
  std::printf("%-18s %.6g", name, *v);
  if (ci) std::printf("  [%.4g, %.4g]", ci->lo, ci->hi);
  std::printf("\n");
}

void PrintText(const m::MetricsReport& r) {
  std::printf("%d frames %dx%d at %g fps (%s), layer %s, region %s: %lld px", r.frames, r.width, r.height, r.fps,
              r.fps_source.c_str(), r.layer.c_str(), r.region.c_str(), r.pixels);
  if (r.nan_pixels) std::printf(" (%lld excluded: NaN/Inf)", r.nan_pixels);
  std::printf("\n");
  std::printf("%-18s %.6g\n", "tv_test", r.tv_test);
  if (!r.reference.empty()) {
    PrintOptional("tv_ref", r.tv_ref);
    const m::TileBlockStatistics::Intervals ci = r.ci95.value_or(m::TileBlockStatistics::Intervals{});
    PrintWithInterval("tv_err", r.tv_err, ci.tv_err);
    if (r.tv_err_floor) std::printf("%-18s %.3g of tv_err is the reference's noise\n", "tv_err_floor", *r.tv_err_floor);
    PrintWithInterval("tv_ratio", r.tv_ratio, ci.tv_ratio);
    PrintWithInterval("energy_bias", r.energy_bias, ci.energy_bias);
    PrintOptional("temporal_diff_err", r.temporal_diff_err);
    PrintOptional("rmse", r.rmse);
    PrintWithInterval("relmse", r.relmse, ci.relmse);
    PrintWithInterval("  temporal part", r.relmse_temporal, ci.relmse_temporal);
    PrintWithInterval("  spatial part", r.relmse_spatial, ci.relmse_spatial);
  }
  std::printf("%-18s %.6g\n", "temporal_diff_test", r.temporal_diff_test);
  if (r.warp_err) std::printf("%-18s %.6g\n", "warp_err", *r.warp_err);
  const m::FlickerResult& f = r.flicker;
  std::printf("flicker of %s (Welch, L = %d, %d segments): 0-2 Hz %.4g | 2-8 Hz %.4g | 8-%g Hz %.4g\n",
              f.signal.c_str(), f.segment_length, f.segments, f.band_low, f.band_mid, r.fps / 2, f.band_high);
  PrintWithInterval("flicker_index", f.flicker_index, r.ci95 ? r.ci95->flicker_index : std::nullopt);
  if (r.sparkles) {
    const m::SparkleReport& s = *r.sparkles;
    auto format = [](const std::optional<double>& v) {
      char text[32];
      if (!v) return std::string("undefined");
      std::snprintf(text, sizeof text, "%.4g", *v);
      return std::string(text);
    };
    auto line = [&](const char* side, const m::SparkleStatistics& x) {
      std::printf("sparkles > %g in %s: %.4g px per frame, variance %.4g, cv %s; lifetime %s frames, birth rate %s "
                  "(motion: %s)\n",
                  s.threshold, side, x.mean_count, x.count_variance, format(x.count_cv).c_str(),
                  format(x.mean_lifetime).c_str(), format(x.birth_rate).c_str(), x.motion.c_str());
    };
    line("test", s.test);
    if (s.reference) {
      line("reference", *s.reference);
      std::printf("sparkles test/reference: mean count %s, count variance %s, lifetime %s\n",
                  format(s.mean_count_ratio).c_str(), format(s.count_variance_ratio).c_str(),
                  format(s.lifetime_ratio).c_str());
    }
  }
  if (r.bootstrap)
    std::printf("95%% intervals: block bootstrap, %d replicates, blocks of %d frames, %dx%d tiles, seed %llu\n",
                r.bootstrap->replicates, r.bootstrap->frame_block, r.bootstrap->tile, r.bootstrap->tile,
                static_cast<unsigned long long>(r.bootstrap->seed));
}

void Run(const MetricsCliOptions& o) {
  m::MetricsOptions options;
  options.test = o.test;
  if (!o.reference.empty()) options.reference = o.reference;
  if (o.fps != 0) {
    if (!(o.fps > 0) || o.fps > 1e6) throw UsageError("--fps must be in (0, 1e6], got " + std::to_string(o.fps));
    options.request.fps = o.fps;
  }
  options.request.layer = o.layer;
  if (!o.mask.empty()) options.mask_file = o.mask;
  options.highlight_mask = o.highlight_mask;
  if (!(o.highlight_threshold >= 0) || !std::isfinite(o.highlight_threshold))
    throw UsageError("--highlight-threshold must be a finite number >= 0");
  // A radius beyond the largest EXR side dilates every mask to the whole frame.
  if (o.highlight_dilate < 0 || o.highlight_dilate > 16384)
    throw UsageError("--highlight-dilate must be in 0..16384 pixels, got " + std::to_string(o.highlight_dilate));
  options.highlight = {o.highlight_threshold, o.highlight_dilate};
  if (o.signal == "error")
    options.signal = m::FlickerSignal::kError;
  else if (o.signal == "test")
    options.signal = m::FlickerSignal::kTest;
  else if (!o.signal.empty())
    throw UsageError("--signal must be error or test, got '" + o.signal + "'");
  if (o.segment < 0 || o.segment == 1) throw UsageError("--segment must be >= 2");
  options.segment_length = o.segment;
  if (!(o.sparkle_threshold >= 0) || !std::isfinite(o.sparkle_threshold)) {
    char given[32];
    std::snprintf(given, sizeof given, "%g", o.sparkle_threshold);
    throw UsageError(std::string("--sparkle-threshold must be a finite number >= 0 (0: no sparkle statistics), got ") +
                     given);
  }
  options.sparkle_threshold = o.sparkle_threshold;
  if (!o.video.empty()) RequireParentDirectory("--video", o.video);
  if (o.slow < 1 || o.slow > 100) throw UsageError("--slow must be 1..100, got " + std::to_string(o.slow));
  if (!o.out.empty()) {
    std::error_code ec;
    const std::filesystem::path out(o.out);
    if (std::filesystem::exists(out, ec) && !std::filesystem::is_directory(out, ec))
      throw UsageError("--out " + o.out + ": exists and is not a directory");
    RequireParentDirectory("--out", o.out);
  }

  std::unique_ptr<m::VideoGrid> video;
  m::FrameObserver observer;
  if (!o.video.empty()) {
    observer = [&](const m::ObservedFrame& frame) -> Status {
      if (!video) {
        m::VideoGridOptions grid;
        grid.labels = {m::SequenceLabel(o.test)};
        grid.with_reference = frame.has_reference;
        grid.width = frame.test.cols, grid.height = frame.test.rows;
        grid.fps = frame.fps;
        grid.slow = o.slow;
        auto opened = m::VideoGrid::Open(o.video, std::move(grid));
        if (!opened) return opened.failure();
        video = std::move(*opened);
      }
      return video->AddFrame({frame.test}, frame.has_reference ? frame.other : cv::Mat());
    };
  }

  std::error_code ec;
  const bool video_existed = !o.video.empty() && std::filesystem::exists(o.video, ec);
  m::MetricsReport report = Take(m::ComputeMetrics(options, observer));
  std::vector<std::string> warnings = report.warnings;
  if (video) Check(video->Finish());
  if (!o.out.empty()) {
    // WriteReportFiles is all or nothing; the video, finished before it, goes
    // with it, so that a failed command leaves no outputs behind.
    const Status written = m::WriteReportFiles(report, o.out, &warnings);
    if (!written && video && !video_existed) std::filesystem::remove(o.video, ec);
    Check(written);
  }
  for (size_t i = report.warnings.size(); i < warnings.size(); ++i) report.warnings.push_back(warnings[i]);
  for (const std::string& w : report.warnings) Warn(w);
  if (o.json)
    std::cout << m::ToJson(report).dump() << "\n";
  else
    PrintText(report);
  // What was written goes to stderr, so that --json output stays one object.
  if (video) std::fprintf(stderr, "shimmer: wrote %s (MP4, %s)\n", o.video.c_str(), video->fourcc_name());
  if (!o.out.empty()) std::fprintf(stderr, "shimmer: wrote maps, spectrum and metrics.json to %s\n", o.out.c_str());
}

}  // namespace

void AddMetricsCommand(CLI::App& app) {
  auto o = std::make_shared<MetricsCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "metrics", "Temporal metrics of an EXR sequence (any renderer): variance, energy bias, flicker spectrum");
  cmd->add_option("TEST", o->test, "Test sequence: directory of EXR frames (sorted by name) or sequence.json")
      ->required();
  cmd->add_option("REF", o->reference, "Reference sequence, same size and length (optional)");
  cmd->add_option("--fps", o->fps, "Frame rate when sequence.json gives none (default 60)");
  cmd->add_option("--layer", o->layer, "EXR layer to measure (default: specular when present, else beauty R,G,B)");
  auto* mask = cmd->add_option("--mask", o->mask, "Region: any image, nonzero pixels are in");
  auto* highlight = cmd->add_flag("--highlight-mask", o->highlight_mask,
                                  "Region: reference specular luminance above the threshold, dilated, union over "
                                  "frames");
  mask->excludes(highlight);
  highlight->excludes(mask);
  cmd->add_option("--highlight-threshold", o->highlight_threshold, "Highlight mask threshold on linear Y")
      ->capture_default_str();
  cmd->add_option("--highlight-dilate", o->highlight_dilate, "Highlight mask dilation radius (pixels)")
      ->capture_default_str();
  cmd->add_option("--signal", o->signal, "Spectrum of: error (T - R, default with REF) or test");
  cmd->add_option("--segment", o->segment, "Welch segment length L (default min(frames, 64))");
  cmd->add_option("--sparkle-threshold", o->sparkle_threshold,
                  "Sparkle statistics: pixels whose Y exceeds this many times their neighbourhood's mean (a "
                  "contrast), counted per frame, their variance over time and lifetime along the motion vectors "
                  "(default 0: off)");
  cmd->add_option("--out", o->out, "Directory for maps (EXR + PNG heatmaps), spectrum CSV/plot, metrics.json");
  cmd->add_option("--video", o->video,
                  "Write an MP4: labelled reference and test, the signed error below the test, a legend (see "
                  "`shimmer video` for several sequences)");
  cmd->add_option("--slow", o->slow, "Video: write each frame N times (slow motion)")->capture_default_str();
  cmd->add_flag("--json", o->json, "Print one JSON object on stdout");
  cmd->callback([o] { Run(*o); });
}

}  // namespace shimmer::cli
