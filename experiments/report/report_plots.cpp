#include <algorithm>
#include <sstream>

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

}  // namespace

std::vector<PlotFile> Plots(const Group& group) {
  const std::string slug = Slug(group.key);
  const Costs c = CostsOf(group);

  std::vector<PlotFile> files;
  // Data and scripts beside the SVGs, so users can restyle them.
  std::ostringstream pts;
  pts << "# ms_per_frame tv_err relmse pareto_tv_err pareto_relmse label\n";
  for (std::size_t i = 0; i < group.rows.size(); ++i)
    pts << c.ms[i] << " " << c.tv_err[i] << " " << c.relmse[i] << " " << c.front_tv_err[i] << " " << c.front_relmse[i]
        << " \"" << Label(*group.rows[i]) << "\"\n";
  pts << "\n\n# supersample-N curve\n";
  for (std::size_t i = 0; i < group.rows.size(); ++i)
    if (IsSupersample(*group.rows[i]))
      pts << c.ms[i] << " " << c.tv_err[i] << " " << c.relmse[i] << " 0 0 \"" << group.rows[i]->job.variant << "\"\n";
  files.push_back({slug + "_pareto.dat", pts.str()});
  for (const auto& [metric, column] : {std::pair<std::string, int>{"tv_err", 2}, {"relmse", 3}}) {
    const std::string y = std::to_string(column), flag = std::to_string(column + 2);
    std::ostringstream ss;
    // Only the front is labelled: twenty labels on a cluster of points
    // would cover each other; the table names every point.
    ss << kTerminal << "set output '" << slug << "_pareto_" << metric << ".svg'\n"
       << "set title " << GnuplotString(group.key + ": speed against " + metric) << "\n"
       << "set xlabel 'GPU ms per frame'\nset ylabel '" << metric << "'\nset logscale y\nset key top right\n"
       << "plot '" << slug << "_pareto.dat' index 0 using 1:" << y << " with points pt 7 title 'variants', \\\n"
       << "     '' index 0 using ($" << flag << " > 0 ? $1 : 1/0):" << y
       << " with points pt 6 ps 2 title 'Pareto front', \\\n"
       << "     '' index 0 using ($" << flag << " > 0 ? $1 : 1/0):" << y
       << ":6 with labels offset 0.8,0.6 left font ',8' notitle, \\\n"
       << "     '' index 1 using 1:" << y << " with linespoints dt 2 title 'supersample-N (equal-time baseline)'\n";
    files.push_back({slug + "_pareto_" + metric + ".gp", ss.str(), true});
  }
  std::ostringstream spectra, sp;
  spectra << "# one block per variant: freq_hz psd\n";
  sp << kTerminal << "set output '" << slug << "_spectra.svg'\n"
     << "set title " << GnuplotString(group.key + ": flicker spectra of the error") << "\n"
     << "set xlabel 'Hz'\nset ylabel 'PSD'\nset logscale y\nset key outside right font ',8'\nplot ";
  int block = 0;
  for (const JobResult* r : group.rows) {
    if (!r->metrics.contains("flicker")) continue;
    const auto& f = r->metrics["flicker"];
    spectra << "# " << Label(*r) << "\n";
    for (std::size_t k = 0; k < f["freq_hz"].size(); ++k)
      spectra << f["freq_hz"][k].get<double>() << " " << std::max(f["psd"][k].get<double>(), 1e-30) << "\n";
    spectra << "\n\n";
    // Colours first, then dash patterns: no two lines look alike.
    sp << (block ? ", \\\n     " : "") << "'" << slug << "_spectra.dat' index " << block
       << " using 1:2 with lines lw 1.5 lc rgb '" << kColours[block % kColourCount] << "' dt "
       << 1 + block / kColourCount << " title " << GnuplotString(Label(*r));
    ++block;
  }
  sp << "\n";
  files.push_back({slug + "_spectra.dat", spectra.str()});
  files.push_back({slug + "_spectra.gp", sp.str(), true});
  return files;
}

}  // namespace shimmer::experiments::report
