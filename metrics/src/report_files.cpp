#include "shimmer/metrics/report_files.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "shimmer/metrics/atomic_file.h"
#include "shimmer/metrics/exr_sequence.h"
#include "shimmer/metrics/heatmap.h"
#include "shimmer/metrics/temporal_sensitivity.h"

namespace shimmer::metrics {

namespace fs = std::filesystem;

namespace {

Status WriteText(const fs::path& file, const std::string& text) {
  const fs::path temporary = TemporaryPathFor(file);
  {
    std::ofstream out(temporary, std::ios::binary);
    out << text;
    if (!out.good()) {
      std::error_code ec;
      fs::remove(temporary, ec);
      return Status::Failure(file.string() + ": cannot write");
    }
  }
  return CommitFile(temporary, file);
}

Status WriteMap(const fs::path& dir, const std::string& name, const cv::Mat& map, const cv::Mat& region,
                HeatmapScaling scaling, const std::string& title) {
  if (Status s = WriteExr(dir / (name + ".exr"), {{"Y", map, false}}); !s) return s;
  const HeatmapRange range = AutoRange(map, region, scaling);
  return WriteImage(dir / (name + ".png"), RenderHeatmap(map, region, scaling, range, title));
}

bool OnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (!path) return false;
  std::stringstream dirs(path);
  std::string d;
  while (std::getline(dirs, d, ':')) {
    std::error_code ec;
    if (!d.empty() && fs::is_regular_file(fs::path(d) / program, ec)) return true;
  }
  return false;
}

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

Status WriteSpectrumPlot(const MetricsReport& report, const fs::path& dir, std::vector<std::string>* warnings) {
  const FlickerResult& f = report.flicker;
  std::ostringstream csv;
  csv.precision(10);
  csv << "freq_hz,psd,watson_gain\n";
  for (size_t k = 0; k < f.psd.size(); ++k)
    csv << f.freq_hz[k] << "," << f.psd[k] << "," << WatsonTemporalGain(f.freq_hz[k]) << "\n";
  if (Status s = WriteText(dir / "spectrum.csv", csv.str()); !s) return s;

  // The script sits beside the data so the plot can be restyled and rerun by hand.
  const std::string partial = TemporaryPathFor(dir / "spectrum.png").filename().string();
  std::ostringstream gp;
  gp << "# Flicker spectrum written by `shimmer metrics`; run: gnuplot spectrum.gp\n"
     << "set terminal pngcairo size 800,480 font 'sans,10'\n"
     << "set output '" << partial << "'\n"
     << "set datafile separator ','\n"
     << "set title 'Flicker spectrum: Welch PSD of " << (f.signal == "error" ? "E = T - R" : "T")
     << " (layer " << report.layer << ", " << report.pixels - report.nan_pixels << " px, L = " << f.segment_length
     << ", " << f.segments << " segments)' noenhanced\n"
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
        "(flicker\\_index)'\n";
  if (Status s = WriteText(dir / "spectrum.gp", gp.str()); !s) return s;

  if (!OnPath("gnuplot")) {
    if (warnings) warnings->push_back("gnuplot not found: wrote spectrum.csv and spectrum.gp but no spectrum.png");
    return Ok();
  }
  const std::string command = "cd " + ShellQuote(dir.string()) + " && gnuplot spectrum.gp >/dev/null 2>&1";
  const int rc = std::system(command.c_str());
  std::error_code ec;
  if (rc != 0 || !fs::exists(dir / partial, ec)) {
    fs::remove(dir / partial, ec);
    if (warnings) warnings->push_back("gnuplot failed on " + (dir / "spectrum.gp").string() + "; no spectrum.png");
    return Ok();
  }
  return CommitFile(dir / partial, dir / "spectrum.png");
}

Status WriteReportFiles(const MetricsReport& report, const fs::path& dir, std::vector<std::string>* warnings) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) return Status::Failure(dir.string() + ": cannot create directory");
  const cv::Mat& region = report.region_mask;
  if (Status s = WriteMap(dir, "tv_test", report.tv_test_map, region, HeatmapScaling::kLog,
                          "temporal variance of T (Y^2)");
      !s)
    return s;
  if (!report.reference.empty()) {
    if (Status s = WriteMap(dir, "tv_ref", report.tv_ref_map, region, HeatmapScaling::kLog,
                            "temporal variance of R (Y^2)");
        !s)
      return s;
    if (Status s = WriteMap(dir, "tv_err", report.tv_err_map, region, HeatmapScaling::kLog,
                            "temporal variance of E = T - R (Y^2)");
        !s)
      return s;
    if (Status s = WriteMap(dir, "energy_bias", report.energy_bias_map, region, HeatmapScaling::kSigned,
                            "energy bias (sum T - sum R) / sum R");
        !s)
      return s;
  }
  if (Status s = WriteSpectrumPlot(report, dir, warnings); !s) return s;
  return WriteText(dir / "metrics.json", ToJson(report).dump(2) + "\n");
}

}  // namespace shimmer::metrics
