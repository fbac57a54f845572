#include "shimmer/metrics/report_files.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "shimmer/core/atomic_file.h"
#include "shimmer/core/gnuplot.h"
#include "shimmer/core/staged_directory.h"
#include "shimmer/metrics/exr_sequence.h"
#include "shimmer/metrics/heatmap.h"
#include "shimmer/metrics/temporal_sensitivity.h"

namespace shimmer::metrics {

namespace fs = std::filesystem;

namespace {

Status WriteMap(const fs::path& dir, const std::string& name, const cv::Mat& map, const cv::Mat& region,
                HeatmapScaling scaling, const std::string& title) {
  if (Status s = WriteExr(dir / (name + ".exr"), map.cols, map.rows, {PlaneOf("Y", map)}); !s) return s;
  const HeatmapRange range = AutoRange(map, region, scaling);
  return WriteImage(dir / (name + ".png"), RenderHeatmap(map, region, scaling, range, title));
}

// The spectrum CSV and script, and its PNG through gnuplot when present, into
// WriteReportFiles' staging directory.
Status WriteSpectrumPlot(const MetricsReport& report, const fs::path& dir, std::vector<std::string>* warnings) {
  const FlickerResult& f = report.flicker;
  std::ostringstream csv;
  csv.precision(10);
  csv << "freq_hz,psd,watson_gain\n";
  for (size_t k = 0; k < f.psd.size(); ++k)
    csv << f.freq_hz[k] << "," << f.psd[k] << "," << WatsonTemporalGain(f.freq_hz[k]) << "\n";
  if (Status s = WriteFileAtomic(dir / "spectrum.csv", csv.str()); !s) return s;

  // The script sits beside the data so the plot can be restyled and rerun by hand.
  std::ostringstream gp;
  gp << "# Flicker spectrum written by `shimmer metrics`; run: gnuplot spectrum.gp\n"
     << "set terminal pngcairo size 800,480 font 'sans,10' noenhanced\n"
     << "set output 'spectrum.png'\n"
     << "set datafile separator ','\n"
     << "set title 'Flicker spectrum: Welch PSD of " << (f.signal == "error" ? "E = T - R" : "T") << " (layer "
     << report.layer << ", " << report.pixels - report.nan_pixels << " px, L = " << f.segment_length << ", "
     << f.segments << " segments)' noenhanced\n"
     << "set xlabel 'frequency (Hz)'\n"
     << "set ylabel 'PSD (Y^2 / Hz)'\n"
     << "set y2label 'Watson 1986 gain |H|^2'\n"
     << "set logscale y\n"
     << "set format y '%.0e'\n"
     << "set y2range [0:1.05]\n"
     << "set y2tics\n"
     << "set ytics nomirror\n"
     << "set grid\n"
     << "set key top right\n"
     << "set arrow from 2, graph 0 to 2, graph 1 nohead dt 2 lc rgb '#888888'\n"
     << "set arrow from 8, graph 0 to 8, graph 1 nohead dt 2 lc rgb '#888888'\n"
     << "plot 'spectrum.csv' skip 1 using 1:($2 > 0 ? $2 : NaN) with linespoints lw 2 pt 7 ps 0.6 lc rgb '#c0392b' "
        "title 'PSD', \\\n"
     << "     '' skip 1 using 1:($3*$3) axes x1y2 with lines dt 3 lw 1.5 lc rgb '#2c3e50' title 'eye weight "
        "(flicker_index)'\n";
  auto plotted = WritePlot(dir, "spectrum.gp", "spectrum.png", gp.str());
  if (!plotted) return plotted.failure();
  if (*plotted && warnings) warnings->push_back(**plotted);
  return Ok();
}

}  // namespace

Status WriteReportFiles(const MetricsReport& report, const fs::path& out, std::vector<std::string>* warnings) {
  // Every file into a staging directory, then renamed together, metrics.json
  // last: a failure part-way leaves the previous outputs as they were.
  auto staged = StagedDirectory::Create(out);
  if (!staged) return staged.failure();
  const fs::path& dir = (*staged)->staging();
  auto in_final_names = [&](Status s) { return s ? s : Status((*staged)->Unstaged(s.failure())); };
  const cv::Mat& region = report.region_mask;
  if (Status s =
          WriteMap(dir, "tv_test", report.tv_test_map, region, HeatmapScaling::kLog, "temporal variance of T (Y^2)");
      !s)
    return in_final_names(s);
  if (!report.reference.empty()) {
    if (Status s =
            WriteMap(dir, "tv_ref", report.tv_ref_map, region, HeatmapScaling::kLog, "temporal variance of R (Y^2)");
        !s)
      return in_final_names(s);
    if (Status s = WriteMap(dir, "tv_err", report.tv_err_map, region, HeatmapScaling::kLog,
                            "temporal variance of E = T - R (Y^2)");
        !s)
      return in_final_names(s);
    if (Status s = WriteMap(dir, "energy_bias", report.energy_bias_map, region, HeatmapScaling::kSigned,
                            "energy bias (sum T - sum R) / sum R");
        !s)
      return in_final_names(s);
  }
  std::vector<std::string> plot_warnings;
  if (Status s = WriteSpectrumPlot(report, dir, &plot_warnings); !s) return in_final_names(s);
  if (warnings)
    for (const std::string& w : plot_warnings)
      warnings->push_back((*staged)->Unstaged({ErrorCode::kInternal, w}).message);
  if (Status s = WriteFileAtomic(dir / "metrics.json", ToJson(report).dump(2) + "\n"); !s) return in_final_names(s);
  return (*staged)->Commit("metrics.json");
}

}  // namespace shimmer::metrics
