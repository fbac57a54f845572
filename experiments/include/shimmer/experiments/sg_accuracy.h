// How close seed 004's SG-light approximations (SpecularTermSgWarp and
// SpecularTermAsgWarp, renderer/include/shimmer/shading/sg.h) come to the
// exact integral of the project's GGX BRDF against the SG light, on a flat
// surface (normal +z, view in the xz plane, F0 0.04), per roughness and view
// angle, over a 7 x 7 grid of light axes around the mirror direction.
//
// The exact integral is estimated per light by the mean of N x N balance-
// heuristic MIS estimates (SgLightSpecularEstimate) at two jittered N x N
// stratified point sets, the BRDF's paired with the light's through a random
// permutation; deterministic (the seed of each light is a hash of alpha, view,
// sharpness, N and the light's place in the grid, so a subset of the table
// reproduces the full table's numbers).
//
// Written by `shimmer sg-accuracy` and, for stores with SG shots, by the
// report's section "SG lighting: accuracy of seed 004's approximations".
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shimmer/core/result.h"
#include "shimmer/shading/sg.h"

namespace shimmer::experiments {

struct SgAccuracyOptions {
  std::vector<double> alphas{0.05, 0.1, 0.2, 0.4, 0.8};  // GGX roughness
  std::vector<double> views_deg{0, 30, 60, 75, 85};      // view angle from the normal, degrees
  double sharpness = 200;                                // the light's lambda (the built-in SG scenes')
  int samples = 64;                                      // reference: samples x samples MIS estimates per light
};

// Bounds: alphas in [1e-4, 1], views in [0, 90), sharpness in (0, 1e6],
// samples in 4..512, 1 to 64 alphas and views. Messages start with the
// field's name ("alphas", "views_deg", "sharpness", "samples").
inline constexpr double kSgAccuracyMinAlpha = 1e-4;
inline constexpr int kSgAccuracyMinSamples = 4;
inline constexpr int kSgAccuracyMaxSamples = 512;
inline constexpr std::size_t kSgAccuracyMaxListSize = 64;
Status ValidateSgAccuracyOptions(const SgAccuracyOptions& options);

// The grid's side: 7 x 7 lights per (alpha, view).
inline constexpr int kSgAccuracyGridSide = 7;
// The grid spans +-2.5 widths of the reflected lobe in each direction.
inline constexpr double kSgAccuracyGridSpan = 2.5;
// Each width is capped at 20 degrees, so that rough lobes stay near the highlight.
inline constexpr double kSgAccuracyMaxWidthDeg = 20;

// Amplitude of an SG light of `sharpness` whose irradiance at normal incidence
// is 3 (the built-in SG scenes' convention): 3 lambda / (2 pi (1 - e^(-2 lambda))).
double SgAccuracyAmplitude(double sharpness);

// The light axes of one (alpha, view): the mirror direction r rotated by
// i * along in the plane of incidence (positive: towards the normal) and then
// by j * across out of it, i, j in {-2.5, ..., 2.5} widths in 7 steps, with
// the e^-1 widths along = sqrt(4 a^2 + 2 / lambda) and across =
// sqrt(4 a^2 (n.v)^2 + 2 / lambda), each capped at 20 degrees. Row-major
// (along outer). Axes below the horizon are kept: their integral is smaller, not 0.
std::vector<glm::dvec3> SgAccuracyLightAxes(double alpha, double view_deg, double sharpness);

// The view direction at `view_deg` from the normal (0, 0, 1), in the xz plane.
glm::dvec3 SgAccuracyView(double view_deg);

// The reference at one light: the mean of the samples x samples MIS estimates
// (channel x) and the standard error of that mean from their spread,
// sqrt(sample variance / count): an upper bound, stratification makes the
// true error smaller.
struct SgReference {
  double mean = 0;
  double stderr_of_mean = 0;
};
SgReference SgLightReference(const shading::Sg<double>& light, double alpha, glm::dvec3 view, int samples,
                             std::uint64_t seed);

// Per (alpha, view) and method.
struct SgMethodError {
  double energy = 0;  // sum(approx) / sum(ref) - 1 over the grid
  double relmse = 0;  // mean over the grid of (approx - ref)^2 / (ref^2 + 0.01)
};

struct SgAccuracyCell {
  double alpha = 0, view_deg = 0;
  SgMethodError sg, asg;
  double ref_sum = 0;         // sum over the grid of the reference
  double ref_rel_stderr = 0;  // standard error of ref_sum over ref_sum (lights independent)
  // Per light, in SgAccuracyLightAxes' order.
  std::vector<glm::dvec3> axes;
  std::vector<double> ref, sg_values, asg_values;
};

struct SgAccuracyTable {
  SgAccuracyOptions options;
  std::vector<SgAccuracyCell> cells;  // alpha-major: cells[i * views + j]
  const SgAccuracyCell& At(std::size_t alpha_index, std::size_t view_index) const {
    return cells[alpha_index * options.views_deg.size() + view_index];
  }
  double MaxRefRelStderr() const;
};

// The measurement; bad options are a kBadInput error.
Result<SgAccuracyTable> MeasureSgAccuracy(const SgAccuracyOptions& options);

// Header and rows of a table (rows alpha, columns view angle), cells "SG / ASG":
// the energies as signed percentages, the relmse as numbers.
struct SgTextTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};
SgTextTable SgEnergyTable(const SgAccuracyTable& table);
SgTextTable SgRelmseTable(const SgAccuracyTable& table);
std::string SgMarkdownTable(const SgTextTable& table);

// What the numbers are, in one paragraph (the report's and sg_accuracy.md's).
std::string SgAccuracyDescription(const SgAccuracyTable& table);

// One row per (alpha, view): alpha, view_deg, sg_energy, asg_energy, sg_relmse,
// asg_relmse, ref_sum, ref_rel_stderr.
std::string SgAccuracyCsv(const SgAccuracyTable& table);
nlohmann::json SgAccuracyJson(const SgAccuracyTable& table);
// Plot data (one block per alpha: view_deg sg_energy_% asg_energy_%, by view)
// and the gnuplot script that draws `stem`.svg from `stem`.dat: energy
// against view angle per alpha, SG warp solid, ASG warp dashed.
std::string SgAccuracyPlotData(const SgAccuracyTable& table);
std::string SgAccuracyPlotScript(const SgAccuracyTable& table, const std::string& stem);

// sg_accuracy.md (the description, both tables, the plot), sg_accuracy.csv,
// sg_accuracy.dat, .gp and .svg into `out_dir` (created), all or none
// (StagedDirectory). Without gnuplot the SVG is missing and `warnings` says why.
Status WriteSgAccuracy(const SgAccuracyTable& table, const std::filesystem::path& out_dir,
                       std::vector<std::string>* warnings);

}  // namespace shimmer::experiments
