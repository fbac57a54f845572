#include "shimmer/experiments/sg_accuracy.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <sstream>
#include <utility>

#include "report_document.h"
#include "shimmer/core/gnuplot.h"
#include "shimmer/core/number_text.h"
#include "shimmer/core/staged_directory.h"
#include "shimmer/experiments/csv.h"
#include "shimmer/experiments/output_files.h"

namespace shimmer::experiments {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kF0 = 0.04;
constexpr double kMaxSharpness = 1e6;  // scene::kMaxSgSharpness: a scene's light cannot be sharper

std::uint64_t SplitMix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// Uniform in [0, 1), 53 bits.
double Uniform(std::uint64_t& state) { return double(SplitMix64(state) >> 11) * 0x1.0p-53; }

std::uint64_t Mix(std::uint64_t h, std::uint64_t value) {
  std::uint64_t state = h ^ value;
  return SplitMix64(state);
}

// The seed of one light: its cell's numbers and its place in the grid, so
// that a light's reference does not depend on the other cells measured.
std::uint64_t LightSeed(double alpha, double view_deg, double sharpness, int samples, int light) {
  std::uint64_t h = 0x5347616363757261ull;  // "SGaccura"
  h = Mix(h, std::bit_cast<std::uint64_t>(alpha));
  h = Mix(h, std::bit_cast<std::uint64_t>(view_deg));
  h = Mix(h, std::bit_cast<std::uint64_t>(sharpness));
  h = Mix(h, std::uint64_t(samples));
  return Mix(h, std::uint64_t(light));
}

// ((i + xi) / n): a jittered coordinate, kept below 1 where rounding would reach it.
double Stratum(int i, int n, std::uint64_t& state) {
  return std::min((double(i) + Uniform(state)) / double(n), std::nextafter(1.0, 0.0));
}

Status ValidateList(const std::vector<double>& values, const char* field, double lo, double hi, bool hi_open) {
  if (values.empty()) return Status::Failure(std::string(field) + " must name at least one value");
  if (values.size() > kSgAccuracyMaxListSize)
    return Status::Failure(std::string(field) + " takes at most " + std::to_string(kSgAccuracyMaxListSize) +
                           " values, got " + std::to_string(values.size()));
  for (double v : values)
    if (!(v >= lo && (hi_open ? v < hi : v <= hi)))
      return Status::Failure(std::string(field) + " must be in [" + NumberText(lo) + ", " + NumberText(hi) +
                             (hi_open ? ")" : "]") + ", got " + NumberText(v));
  return Ok();
}

std::string Percent(double v) { return std::isfinite(v) ? FormatNumber(100 * v, "%+.1f") + " %" : "n/a"; }
std::string Small(double v) { return std::isfinite(v) ? FormatNumber(v, "%.3g") : "n/a"; }

std::vector<std::string> Header(const SgAccuracyTable& table) {
  std::vector<std::string> header{"α \\ view"};
  for (double v : table.options.views_deg) header.push_back(FormatNumber(v, "%g") + "°");
  return header;
}

std::string Number(double v) {
  if (!std::isfinite(v)) return "NaN";
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

constexpr const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
constexpr int kColourCount = int(sizeof kColours / sizeof kColours[0]);

}  // namespace

Status ValidateSgAccuracyOptions(const SgAccuracyOptions& o) {
  if (Status s = ValidateList(o.alphas, "alphas", kSgAccuracyMinAlpha, 1, false); !s) return s;
  if (Status s = ValidateList(o.views_deg, "views_deg", 0, 90, true); !s) return s;
  if (!(o.sharpness > 0 && o.sharpness <= kMaxSharpness))
    return Status::Failure("sharpness must be in (0, " + NumberText(kMaxSharpness) + "], got " +
                           NumberText(o.sharpness));
  if (o.samples < kSgAccuracyMinSamples || o.samples > kSgAccuracyMaxSamples)
    return Status::Failure("samples must be in " + std::to_string(kSgAccuracyMinSamples) + ".." +
                           std::to_string(kSgAccuracyMaxSamples) + " (per axis), got " + std::to_string(o.samples));
  return Ok();
}

double SgAccuracyAmplitude(double sharpness) { return 3 * sharpness / (2 * kPi * -std::expm1(-2 * sharpness)); }

glm::dvec3 SgAccuracyView(double view_deg) {
  const double t = view_deg * kPi / 180;
  return {std::sin(t), 0, std::cos(t)};
}

std::vector<glm::dvec3> SgAccuracyLightAxes(double alpha, double view_deg, double sharpness) {
  const glm::dvec3 v = SgAccuracyView(view_deg);
  const glm::dvec3 r(-v.x, 0, v.z);  // v reflected about (0, 0, 1)
  const double nv = v.z, a2 = alpha * alpha, w_light2 = 2 / sharpness;
  const double cap = kSgAccuracyMaxWidthDeg * kPi / 180;
  const double along = std::min(std::sqrt(4 * a2 + w_light2), cap);
  const double across = std::min(std::sqrt(4 * a2 * nv * nv + w_light2), cap);
  // In the plane of incidence, perpendicular to r, on the normal's side.
  const glm::dvec3 in_plane = glm::normalize(glm::cross(glm::dvec3(0, 1, 0), r));
  const glm::dvec3 out_of_plane(0, 1, 0);
  std::vector<glm::dvec3> axes;
  const int half = kSgAccuracyGridSide / 2;
  for (int i = -half; i <= half; ++i) {
    const double t_along = kSgAccuracyGridSpan * double(i) / double(half) * along;
    const glm::dvec3 ri = std::cos(t_along) * r + std::sin(t_along) * in_plane;  // in the xz plane
    for (int j = -half; j <= half; ++j) {
      const double t_across = kSgAccuracyGridSpan * double(j) / double(half) * across;
      axes.push_back(glm::normalize(std::cos(t_across) * ri + std::sin(t_across) * out_of_plane));
    }
  }
  return axes;
}

SgReference SgLightReference(const shading::Sg<double>& light, double alpha, glm::dvec3 view, int samples,
                             std::uint64_t seed) {
  const int n = samples;
  const std::size_t count = std::size_t(n) * std::size_t(n);
  std::uint64_t state = seed;
  // The BRDF's points: jittered strata, paired with the light's by a random permutation.
  std::vector<glm::dvec2> brdf(count);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) brdf[std::size_t(i) * n + j] = {Stratum(i, n, state), Stratum(j, n, state)};
  for (std::size_t k = count - 1; k > 0; --k) {
    const std::size_t other = std::size_t(SplitMix64(state) % (k + 1));
    std::swap(brdf[k], brdf[other]);
  }
  const glm::dvec3 normal(0, 0, 1), f0(kF0);
  double mean = 0, m2 = 0;  // Welford
  std::size_t k = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j, ++k) {
      const glm::dvec2 u_light(Stratum(i, n, state), Stratum(j, n, state));
      const double x = shading::SgLightSpecularEstimate<double>(light, normal, alpha, view, f0, u_light, brdf[k]).x;
      const double d = x - mean;
      mean += d / double(k + 1);
      m2 += d * (x - mean);
    }
  SgReference r;
  r.mean = mean;
  r.stderr_of_mean = std::sqrt(m2 / double(count - 1) / double(count));
  return r;
}

double SgAccuracyTable::MaxRefRelStderr() const {
  double worst = 0;
  for (const SgAccuracyCell& c : cells) worst = std::max(worst, c.ref_rel_stderr);
  return worst;
}

Result<SgAccuracyTable> MeasureSgAccuracy(const SgAccuracyOptions& options) {
  if (Status s = ValidateSgAccuracyOptions(options); !s) return s.failure();
  SgAccuracyTable table;
  table.options = options;
  const double amplitude = SgAccuracyAmplitude(options.sharpness);
  const glm::dvec3 normal(0, 0, 1), f0(kF0);
  for (double alpha : options.alphas)
    for (double view_deg : options.views_deg) {
      SgAccuracyCell c;
      c.alpha = alpha, c.view_deg = view_deg;
      c.axes = SgAccuracyLightAxes(alpha, view_deg, options.sharpness);
      const glm::dvec3 view = SgAccuracyView(view_deg);
      double sum_sg = 0, sum_asg = 0, var_sum = 0, rel_sg = 0, rel_asg = 0;
      for (std::size_t l = 0; l < c.axes.size(); ++l) {
        const shading::Sg<double> light{c.axes[l], options.sharpness, glm::dvec3(amplitude)};
        const SgReference ref =
            SgLightReference(light, alpha, view, options.samples,
                             LightSeed(alpha, view_deg, options.sharpness, options.samples, int(l)));
        const double sg = shading::SpecularTermSgWarp<double>(light, normal, alpha, view, f0).x;
        const double asg = shading::SpecularTermAsgWarp<double>(light, normal, alpha, view, f0).x;
        c.ref.push_back(ref.mean), c.sg_values.push_back(sg), c.asg_values.push_back(asg);
        c.ref_sum += ref.mean, sum_sg += sg, sum_asg += asg;
        var_sum += ref.stderr_of_mean * ref.stderr_of_mean;  // independent lights: variances add
        const double denominator = ref.mean * ref.mean + 0.01;
        rel_sg += (sg - ref.mean) * (sg - ref.mean) / denominator;
        rel_asg += (asg - ref.mean) * (asg - ref.mean) / denominator;
      }
      const double lights = double(c.axes.size());
      const double nan = std::nan("");
      c.sg.energy = c.ref_sum > 0 ? sum_sg / c.ref_sum - 1 : nan;
      c.asg.energy = c.ref_sum > 0 ? sum_asg / c.ref_sum - 1 : nan;
      c.sg.relmse = rel_sg / lights;
      c.asg.relmse = rel_asg / lights;
      c.ref_rel_stderr = c.ref_sum > 0 ? std::sqrt(var_sum) / c.ref_sum : nan;
      table.cells.push_back(std::move(c));
    }
  return table;
}

namespace {
// Rows alpha, columns view angle, each cell "SG / ASG" of one method field.
template <class Format>
SgTextTable MethodTable(const SgAccuracyTable& table, double SgMethodError::*field, Format format) {
  SgTextTable t{Header(table), {}};
  for (std::size_t i = 0; i < table.options.alphas.size(); ++i) {
    std::vector<std::string> row{FormatNumber(table.options.alphas[i], "%g")};
    for (std::size_t j = 0; j < table.options.views_deg.size(); ++j) {
      const SgAccuracyCell& c = table.At(i, j);
      row.push_back(format(c.sg.*field) + " / " + format(c.asg.*field));
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}
}  // namespace

SgTextTable SgEnergyTable(const SgAccuracyTable& table) { return MethodTable(table, &SgMethodError::energy, Percent); }
SgTextTable SgRelmseTable(const SgAccuracyTable& table) { return MethodTable(table, &SgMethodError::relmse, Small); }

std::string SgMarkdownTable(const SgTextTable& table) { return report::MarkdownTable(table.header, table.rows); }

std::string SgAccuracyDescription(const SgAccuracyTable& table) {
  const SgAccuracyOptions& o = table.options;
  const int lights = kSgAccuracyGridSide * kSgAccuracyGridSide;
  return "Seed 004's SG warp (`SpecularTermSgWarp`) and ASG warp (`SpecularTermAsgWarp`) against the exact "
         "integral of the renderer's GGX BRDF (GGX D, height-correlated Smith G2, Schlick F0 = 0.04) under an SG "
         "light of sharpness λ = " +
         FormatNumber(o.sharpness, "%g") +
         " with irradiance 3 at normal incidence, on a flat surface, per roughness α (rows) and view angle from the "
         "normal (columns). Each cell is " +
         std::to_string(lights) + " light axes on a " + std::to_string(kSgAccuracyGridSide) + " × " +
         std::to_string(kSgAccuracyGridSide) +
         " grid about the mirror direction, ±2.5 e⁻¹ widths of the reflected lobe along and across the plane of "
         "incidence (√(4α² + 2/λ) and √(4α²(n·v)² + 2/λ), each at most 20°; axes below the horizon kept). Energy: "
         "Σ approx / Σ exact − 1 over the grid, signed; relmse: the mean over the grid of (approx − exact)² / "
         "(exact² + 0.01) (docs/metrics.md). Cells: SG warp / ASG warp. The exact integral per light is the mean "
         "of " +
         std::to_string(o.samples) + " × " + std::to_string(o.samples) +
         " balance-heuristic MIS estimates (SG directions and GGX visible normals) on stratified points; the "
         "relative standard error of a cell's Σ exact is at most " +
         FormatNumber(100 * table.MaxRefRelStderr(), "%.2g") +
         " % (from the estimates' spread: an upper bound, the strata make it smaller).";
}

std::string SgAccuracyCsv(const SgAccuracyTable& table) {
  CsvTable csv(
      {"alpha", "view_deg", "sg_energy", "asg_energy", "sg_relmse", "asg_relmse", "ref_sum", "ref_rel_stderr"});
  for (const SgAccuracyCell& c : table.cells)
    csv.AddRow({CsvNumber(c.alpha), CsvNumber(c.view_deg), CsvNumber(c.sg.energy), CsvNumber(c.asg.energy),
                CsvNumber(c.sg.relmse), CsvNumber(c.asg.relmse), CsvNumber(c.ref_sum), CsvNumber(c.ref_rel_stderr)});
  return csv.Text();
}

nlohmann::json SgAccuracyJson(const SgAccuracyTable& table) {
  const SgAccuracyOptions& o = table.options;
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json cells = nlohmann::json::array();
  for (const SgAccuracyCell& c : table.cells)
    cells.push_back({{"alpha", c.alpha},
                     {"view_deg", c.view_deg},
                     {"sg", {{"energy", number(c.sg.energy)}, {"relmse", number(c.sg.relmse)}}},
                     {"asg", {{"energy", number(c.asg.energy)}, {"relmse", number(c.asg.relmse)}}},
                     {"ref_sum", number(c.ref_sum)},
                     {"ref_rel_stderr", number(c.ref_rel_stderr)}});
  return {{"alphas", o.alphas},
          {"views_deg", o.views_deg},
          {"sharpness", o.sharpness},
          {"amplitude", SgAccuracyAmplitude(o.sharpness)},
          {"samples", o.samples},
          {"f0", kF0},
          {"lights_per_cell", kSgAccuracyGridSide * kSgAccuracyGridSide},
          {"cells", cells}};
}

std::string SgAccuracyPlotData(const SgAccuracyTable& table) {
  const SgAccuracyOptions& o = table.options;
  std::vector<std::size_t> by_view(o.views_deg.size());
  std::iota(by_view.begin(), by_view.end(), 0);
  std::stable_sort(by_view.begin(), by_view.end(),
                   [&](std::size_t a, std::size_t b) { return o.views_deg[a] < o.views_deg[b]; });
  std::ostringstream data;
  data << "# one block per alpha: view_deg sg_energy_percent asg_energy_percent\n";
  for (std::size_t i = 0; i < o.alphas.size(); ++i) {
    data << "# alpha " << Number(o.alphas[i]) << "\n";
    for (std::size_t j : by_view) {
      const SgAccuracyCell& c = table.At(i, j);
      data << Number(c.view_deg) << " " << Number(100 * c.sg.energy) << " " << Number(100 * c.asg.energy) << "\n";
    }
    data << "\n\n";
  }
  return data.str();
}

std::string SgAccuracyPlotScript(const SgAccuracyTable& table, const std::string& stem) {
  const SgAccuracyOptions& o = table.options;
  std::ostringstream gp;
  gp << "set terminal svg size 900,560 dynamic noenhanced\nset output " << GnuplotString(stem + ".svg") << "\n"
     << "set title "
     << GnuplotString("Seed 004 under an SG light of sharpness " + FormatNumber(o.sharpness, "%g") +
                      ": energy error (SG warp solid, ASG warp dashed)")
     << "\nset xlabel 'view angle from the normal (degrees)'\nset ylabel 'sum(approx) / sum(exact) - 1 (%)'\n"
     << "set xzeroaxis lt 1 lc rgb '#999999'\nset key outside right top font ',9'\nset grid\nplot ";
  for (std::size_t i = 0; i < o.alphas.size(); ++i) {
    const std::string colour = kColours[i % kColourCount];
    const std::string alpha = FormatNumber(o.alphas[i], "%g");
    gp << (i ? ", \\\n     " : "") << GnuplotString(stem + ".dat") << " index " << i
       << " using 1:2 with linespoints pt 7 lw 1.5 lc rgb '" << colour << "' dt 1 title "
       << GnuplotString("SG warp, alpha " + alpha) << ", \\\n     " << GnuplotString(stem + ".dat") << " index " << i
       << " using 1:3 with linespoints pt 6 lw 1.5 lc rgb '" << colour << "' dt 2 title "
       << GnuplotString("ASG warp, alpha " + alpha);
  }
  gp << "\n";
  return gp.str();
}

Status WriteSgAccuracy(const SgAccuracyTable& table, const std::filesystem::path& out_dir,
                       std::vector<std::string>* warnings) {
  auto staged = StagedDirectory::Create(out_dir);
  if (!staged) return staged.failure();
  StagedDirectory& dir = **staged;
  const std::string stem = "sg_accuracy";
  std::ostringstream md;
  md << "# SG lighting: accuracy of seed 004's approximations\n\n"
     << "Generated by `shimmer sg-accuracy`; the numbers: [" << stem << ".csv](" << stem << ".csv).\n\n"
     << SgAccuracyDescription(table) << "\n\n"
     << "## Energy: Σ approx / Σ exact − 1 (SG warp / ASG warp)\n\n"
     << SgMarkdownTable(SgEnergyTable(table)) << "\n"
     << "## relmse (SG warp / ASG warp)\n\n"
     << SgMarkdownTable(SgRelmseTable(table)) << "\n"
     << "![energy error against view angle per α](" << stem << ".svg)\n";
  if (Status s = dir.Write(stem + ".csv", SgAccuracyCsv(table)); !s) return s;
  if (Status s = dir.Write(stem + ".dat", SgAccuracyPlotData(table)); !s) return s;
  auto plotted = WritePlot(dir.staging(), stem + ".gp", stem + ".svg", SgAccuracyPlotScript(table, stem));
  if (!plotted) return dir.Unstaged(plotted.failure());
  if (*plotted && warnings) warnings->push_back(dir.Unstaged(Error{ErrorCode::kInternal, **plotted}).message);
  if (Status s = dir.Write(stem + ".md", md.str()); !s) return s;
  return dir.Commit(stem + ".md");
}

}  // namespace shimmer::experiments
