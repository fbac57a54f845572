#include <algorithm>
#include <cmath>
#include <sstream>

#include "decision_rule.h"
#include "report_parts.h"
#include "shimmer/experiments/output_files.h"
#include "shimmer/experiments/report.h"

namespace shimmer::experiments::report {

namespace {

// Twenty distinguishable colours (Tableau 20): gnuplot's own cycle repeats
// after eight, and a group has up to twenty variants.
constexpr const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
                                    "#7f7f7f", "#bcbd22", "#17becf", "#aec7e8", "#ffbb78", "#98df8a", "#ff9896",
                                    "#c5b0d5", "#c49c94", "#f7b6d2", "#c7c7c7", "#dbdb8d", "#9edae5"};
constexpr int kColourCount = int(sizeof kColours / sizeof kColours[0]);

// Plain text: gnuplot's enhanced mode would set "tv_err" as tv with a subscript.
constexpr const char* kTerminal = "set terminal svg size 900,560 dynamic noenhanced\n";

std::string Number(double v) {
  if (std::isnan(v)) return "NaN";
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

}  // namespace

std::vector<PlotFile> Plots(const Group& group) {
  const std::string slug = Slug(group.key);
  const Costs c = CostsOf(group);

  std::vector<PlotFile> files;
  if (!c.ms.empty()) {
    // Data and scripts beside the SVGs, so users can restyle them.
    std::ostringstream pts;
    pts << "# ms_per_frame tv_err relmse pareto_tv_err pareto_relmse label\n# ms: " << c.source << "\n";
    for (std::size_t i = 0; i < group.rows.size(); ++i)
      pts << Number(c.ms[i]) << " " << Number(c.tv_err[i]) << " " << Number(c.relmse[i]) << " " << c.front_tv_err[i]
          << " " << c.front_relmse[i] << " \"" << Label(*group.rows[i]) << "\"\n";
    pts << "\n\n# supersample-N curve\n";
    for (std::size_t i = 0; i < group.rows.size(); ++i)
      if (IsSupersample(*group.rows[i]))
        pts << Number(c.ms[i]) << " " << Number(c.tv_err[i]) << " " << Number(c.relmse[i]) << " 0 0 \""
            << group.rows[i]->job.variant << "\"\n";
    files.push_back({slug + "_pareto.dat", pts.str()});
    const std::string xlabel = c.source.rfind("benchmark", 0) == 0 ? "benchmark GPU ms per frame"
                                                                   : "metric render GPU ms per frame (no benchmark)";
    for (const auto& [metric, column] : {std::pair<std::string, int>{"tv_err", 2}, {"relmse", 3}}) {
      const std::vector<double>& err = column == 2 ? c.tv_err : c.relmse;
      const std::vector<bool>& front = column == 2 ? c.front_tv_err : c.front_relmse;
      // The front's points are numbered in order of cost and named in the
      // key: names written beside clustered points would cover each other.
      std::vector<int> order;
      for (std::size_t i = 0; i < front.size(); ++i)
        if (front[i] && !std::isnan(err[i])) order.push_back(int(i));
      std::sort(order.begin(), order.end(), [&](int a, int b) { return c.ms[a] < c.ms[b]; });
      std::ostringstream numbered;
      numbered << "# ms error number\n";
      for (std::size_t k = 0; k < order.size(); ++k)
        numbered << Number(c.ms[order[k]]) << " " << Number(err[order[k]]) << " " << k + 1 << "\n";
      const std::string front_file = slug + "_front_" + metric + ".dat";
      files.push_back({front_file, numbered.str()});
      std::ostringstream ss;
      ss << kTerminal << "set output '" << slug << "_pareto_" << metric << ".svg'\n"
         << "set title " << GnuplotString(group.key + ": speed against " + metric) << "\n"
         << "set xlabel '" << xlabel << "'\nset ylabel '" << metric << "'\nset logscale y\n"
         << "set key outside right top font ',9'\n"
         << "plot '" << slug << "_pareto.dat' index 0 using 1:" << column << " with points pt 7 lc rgb '#1f77b4' "
         << "title 'variants', \\\n"
         << "     '" << front_file << "' using 1:2 with points pt 6 ps 2 lc rgb '#d62728' title 'Pareto front', \\\n"
         << "     '" << front_file << "' using 1:2:3 with labels offset 1.2,0.8 font ',9' notitle, \\\n"
         << "     '" << slug << "_pareto.dat' index 1 using 1:" << column
         << " with linespoints dt 2 lc rgb '#555555' title 'supersample-N (brute force)'";
      for (std::size_t k = 0; k < order.size(); ++k)
        ss << ", \\\n     keyentry with points pt 6 lc rgb '#d62728' title "
           << GnuplotString(std::to_string(k + 1) + ": " + Label(*group.rows[order[k]]));
      ss << "\n";
      files.push_back({slug + "_pareto_" + metric + ".gp", ss.str(), true});
    }
  }
  std::ostringstream spectra, sp;
  spectra << "# one block per variant: freq_hz psd\n";
  sp << kTerminal << "set output '" << slug << "_spectra.svg'\n"
     << "set title " << GnuplotString(group.key + ": flicker spectra of the error") << "\n"
     << "set xlabel 'Hz'\nset ylabel 'PSD'\nset logscale y\nset key outside right font ',8'\nplot ";
  int block = 0;
  for (const JobResult* r : group.rows) {
    if (!r->metrics.contains("flicker") || !r->metrics["flicker"].contains("freq_hz")) continue;
    const auto& f = r->metrics["flicker"];
    spectra << "# " << Label(*r) << "\n";
    for (std::size_t k = 0; k < f["freq_hz"].size() && k < f["psd"].size(); ++k)
      spectra << f["freq_hz"][k].get<double>() << " " << std::max(f["psd"][k].get<double>(), 1e-30) << "\n";
    spectra << "\n\n";
    // Colours first, then dash patterns: no two lines look alike.
    sp << (block ? ", \\\n     " : "") << "'" << slug << "_spectra.dat' index " << block
       << " using 1:2 with lines lw 1.5 lc rgb '" << kColours[block % kColourCount] << "' dt "
       << 1 + block / kColourCount << " title " << GnuplotString(Label(*r));
    ++block;
  }
  sp << "\n";
  if (block > 0) {
    files.push_back({slug + "_spectra.dat", spectra.str()});
    files.push_back({slug + "_spectra.gp", sp.str(), true});
  }
  return files;
}

std::vector<PlotFile> Heatmap(const std::vector<VariantSummary>& variants, const std::vector<const Group*>& groups) {
  std::ostringstream data, crosses, gp;
  data << "# table variant log10(tv_err / tv_err(none)): one block per table\n";
  crosses << "# table variant: |energy_bias| > " << kEnergyTolerance << "\n";
  int crossed = 0;
  double extent = 0.5;
  for (std::size_t x = 0; x < groups.size(); ++x) {
    for (std::size_t y = 0; y < variants.size(); ++y) {
      double value = kNaN;
      for (const Sample& s : variants[y].samples)
        if (s.group == groups[x]) {
          if (s.ratio > 0) value = std::log10(s.ratio);
          if (std::abs(s.energy_bias) > kEnergyTolerance) crosses << x << " " << y << "\n", ++crossed;
        }
      if (!std::isnan(value)) extent = std::max(extent, std::min(3.0, std::abs(value)));
      data << x << " " << y << " " << Number(value) << "\n";
    }
    data << "\n";
  }
  if (groups.empty() || variants.empty()) return {};
  const int width = 360 + 13 * int(groups.size()), height = 330 + 15 * int(variants.size());
  gp << "set terminal svg size " << width << "," << height << " dynamic noenhanced\nset output 'heatmap.svg'\n"
     << "set title 'log10 of tv_err / tv_err(none): blue steadier, red less steady; x: |energy_bias| > 0.10'\n"
     << "set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 '#b2182b')\n"
     << "set cbrange [" << -extent << ":" << extent << "]\nset cblabel 'log10 ratio to none'\n"
     << "set xrange [-0.5:" << groups.size() - 0.5 << "]\nset yrange [" << variants.size() - 0.5 << ":-0.5]\n"
     << "set tics scale 0\nset xtics rotate by 60 right font ',8' (";
  for (std::size_t x = 0; x < groups.size(); ++x) gp << (x ? ", " : "") << GnuplotString(groups[x]->key) << " " << x;
  gp << ")\nset ytics font ',9' (";
  for (std::size_t y = 0; y < variants.size(); ++y)
    gp << (y ? ", " : "") << GnuplotString(variants[y].label) << " " << y;
  gp << ")\nset bmargin 16\nset lmargin 28\nunset key\n"
     << "plot 'heatmap.dat' using 1:2:3 with image pixels";
  // gnuplot refuses a file without points: no crosses, no second plot.
  if (crossed) gp << ", \\\n     'heatmap_crosses.dat' using 1:2 with points pt 2 ps 0.6 lc rgb 'black'";
  gp << "\n";
  return {{"heatmap.dat", data.str()}, {"heatmap_crosses.dat", crosses.str()}, {"heatmap.gp", gp.str(), true}};
}

}  // namespace shimmer::experiments::report
