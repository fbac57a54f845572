// The one rule by which a report calls a variant better than `none` in a
// table, two variants tied, and a cell's pick (docs/method.md, "Decision
// rule"). The overview, every shot's verdict column, the glint part, the
// engine-settings part and fit.md all decide through this file.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "report_parts.h"
#include "shimmer/metrics/block_bootstrap.h"

namespace shimmer::experiments::report {

// A filter must keep the highlight: 10 % of its energy is about the step in
// brightness a viewer notices in a small highlight (luminance Weber
// fractions are a few per cent on a display), and it is five times the
// typical width of `none`'s own energy interval in the standard spec
// (median 0.018), so an interval that misses ±10 % is a real loss.
constexpr double kEnergyTolerance = 0.10;

// A filter trades flicker for blur. Its spatial error (relmse_spatial, the
// temporal mean's error) may exceed `none`'s by at most this factor, with
// intervals, before the trade counts against it: half as large again is
// visibly softer in a still frame, and the blurs that win on flicker alone
// in the standard spec reached 40x and 83x `none`'s, far outside it.
constexpr double kSpatialTolerance = 1.5;

// When the reference's own noise is more than half of the uncertainty of
// the comparison, the comparison describes the reference rather than the
// variant: a tie there is "unresolved", not "no difference". A row and its
// `none` measured on the same draws are compared paired (their tv_err
// difference, in which the reference's noise, common to both, cancels but
// for a cross term: NoiseShare); otherwise the share is tv_err_floor, the
// part of either row's tv_err that the noise explains ...
constexpr double kNoiseShareLimit = 0.5;

// ... unless that noise is itself too faint to hide a flicker anyone could
// see. Its contrast sqrt(F) / mean luminance (F: the variance the
// reference's noise adds, ref_noise; over the row's region) below 1 % is
// under the smallest temporal modulation the eye detects at display
// luminances and the 2-15 Hz a 30-60 fps sequence flickers at (de Lange
// 1958, Kelly 1961: thresholds of 0.5-2 % Michelson contrast, √2 times an
// RMS contrast): whatever the reference cannot tell apart there, a viewer
// cannot either, and the tie is a tie. Rough materials (α 0.5) where
// nothing flickers are most of these rows: a better reference would only
// make `none`'s tiny tv_err and its noise smaller together (their share
// stays ≈ 1).
constexpr double kVisibleContrast = 0.01;

// Within 2 % of `none` in both tv_err and the joint error, a variant does
// not change what is measured (a clamp that never engages, supersample-1):
// "no effect", never a pick.
constexpr double kNilEffect = 0.02;

// Glints: a filter that shows fewer than half or more than twice the
// reference's sparkles per frame changes the material's look (glittering
// paint reads as satin, or as noise), however steady it is; so does one
// whose sparkles live half or twice as long (they twinkle or smear). The
// sparkle count ratio and the lifetime ratio (docs/metrics.md, "Sparkle
// statistics") must stay within [1/kSparkleTolerance, kSparkleTolerance],
// and the count's variance over frames, which scales as the count's square
// (a count half as large and as steady has a quarter of the variance),
// within the square of that range.
constexpr double kSparkleTolerance = 2.0;

// A pick must be better than `none` in at least this share of its cell's
// tables: a filter that helps in a minority of cases is not an answer.
constexpr double kPickShare = 0.5;

// What the rule reads of one row: point values and 95 % intervals of tv_err,
// the joint error (relmse), its spatial part and the energy bias, and the
// share of tv_err that the reference's noise explains (tv_err_floor).
struct Evidence {
  double tv_err = kNaN, joint = kNaN, spatial = kNaN, energy_bias = kNaN, noise_share = kNaN;
  double sparkle_count_ratio = kNaN;  // with sparkle statistics: test's mean count over the reference's
  double sparkle_variance_ratio = kNaN, sparkle_lifetime_ratio = kNaN;  // the count's variance, a sparkle's life
  // A glint material: judged by its sparkles instead of its spatial error (Decide).
  bool glint = false;
  bool smooth_limit = false;  // the variant is a glint material's limit without sparkles (glints-smooth)
  double noise_contrast = kNaN;       // sqrt(ref_noise) / ref_mean; NaN in stores measured before it
  Interval tv_err_ci, joint_ci, spatial_ci, energy_ci;
  // For paired comparisons: the bootstrap's draws (null: compare unpaired),
  // and what the reference noise's share of a paired difference needs.
  std::shared_ptr<const metrics::BootstrapDraws> draws;
  std::string reference_id;  // rows pair only against one reference: its noise is what cancels
  double tv_test = kNaN, ref_noise = kNaN, joint_noise_sigma = kNaN;
  int frames = 0;
  long long pixels = 0;
};

// a's tv_err minus b's with its 95 % interval, when their draws pair: the
// bootstrap interval of the replicates' differences, widened in quadrature
// by the reference noise's cross term (metrics::PairedNoiseSigma), and that
// term's share of the interval's half-width.
struct PairedComparison {
  double difference = kNaN;
  Interval ci;
  double noise_share = kNaN;
};
std::optional<PairedComparison> PairedTvErr(const Evidence& a, const Evidence& b);
// The same for the joint error (relmse), widened by the two rows' noise
// sigmas summed (their noise is shared, its correlation unknown).
std::optional<PairedComparison> PairedJoint(const Evidence& a, const Evidence& b);
// The reference noise's share of what a comparison of a with b ranks: of
// the paired difference's half-width when they pair, else the larger
// tv_err_floor of the two.
double NoiseShare(const Evidence& a, const Evidence& b);
// From a row's metrics; the spatial part falls back to relmse in stores
// measured before the split.
Evidence EvidenceOf(const JobResult& row);

enum class Outcome {
  kBetter,       // steadier by intervals, no blur beyond kSpatialTolerance, energy within kEnergyTolerance
  kTied,         // tv_err intervals overlap
  kNoEffect,     // within kNilEffect of `none` in tv_err and the joint error
  kBlurrier,     // steadier, but its spatial error's interval lies above kSpatialTolerance x none's
  kLosesEnergy,  // steadier, but its energy interval misses ±kEnergyTolerance
  kLosesGlints,  // steadier, but a sparkle ratio leaves its tolerance (kSparkleTolerance)
  kSmoothLimit,  // the glint material's limit without sparkles: a bound, not a filter to pick
  kLessSteady,   // tv_err interval wholly above none's
  kUnresolved,   // tied where the reference's noise is over kNoiseShareLimit of the comparison
                 // (NoiseShare) and its contrast is not below kVisibleContrast (or not known)
  kBaseline,     // the row is `none`
  kUnknown       // an interval is missing
};
Outcome Decide(const Evidence& variant, const Evidence& none);
// The reference's noise is a large share of the comparison (NoiseShare
// over kNoiseShareLimit) but too faint to be seen (kVisibleContrast): a tie
// there is a tie. What the reports count beside the unresolved rows.
bool NoiseBelowVisibility(const Evidence& variant, const Evidence& none);
std::string OutcomeText(Outcome outcome);  // "better", "≈ none", "blurrier", ...

// Two values with intervals, lower is better: kBetter only when a's interval
// lies wholly below b's, else tied (kIndistinguishable). Every "lower",
// "wins" or "fitted better" of a report is this test, or SeparatePaired.
Verdict Separate(Interval a, Interval b);
// a against b by the interval of a - b: kBetter when it lies below 0.
Verdict SeparatePaired(const PairedComparison& a_minus_b);

// The rule in words, for the reports' method sections.
std::string DecisionRuleText();

// The rows of the answer grid: geometry classes, then normal-mapped, SG-lit
// and glint materials as their own rows. A scene file's geometry_class is
// a row of its own (docs/scenes.md), placed before "other".
std::string CellRowOf(const Group& group);
// `rows` (CellRowOf's values) in the grid's order: the built-in classes in
// theirs, each scene-declared one before "other", alphabetically.
std::vector<std::string> CellRowsInOrder(const std::set<std::string>& rows);
const std::vector<std::string>& RoughnessBands();

// One variant in one cell.
struct CellCandidate {
  std::string label;
  bool supersample = false;
  int tables = 0;      // the cell's tables it was measured in
  int better = 0;      // ... and called better than `none` there
  int no_effect = 0;   // ... and of no effect
  int unresolved = 0;  // ... and unresolved
  int energy_within = 0;  // ... with its energy interval meeting ±kEnergyTolerance
  double share = kNaN;  // better / the tables of the set it was ranked in
  Quartiles joint_ratio, tv_err_ratio, energy_bias;  // over the tables, ratios to `none`
  std::map<std::string, Quartiles> cost;  // benchmark ratio_to_none by device, never mixed
  std::vector<std::pair<const Group*, const JobResult*>> rows;
  bool Eligible(int cell_tables) const;
};

// The variants of a set of tables (not `none`), each decided against its
// table's `none`: eligible for a pick first, by median joint-error ratio;
// then by how often better.
std::vector<CellCandidate> Candidates(const std::vector<const Group*>& groups);

struct CellAnswer {
  std::string row, band;  // CellRows() x RoughnessBands()
  int tables = 0, shots = 0;
  std::vector<CellCandidate> candidates;  // eligible first (by median joint ratio), then by share
  const CellCandidate* pick = nullptr;    // null: keep `none`
  const CellCandidate* runner_up = nullptr;
  int ahead = 0, behind = 0, tied = 0;  // pick's joint error against the runner-up's, per shared table
  bool pick_ahead = false;              // ahead in at least half the shared tables and behind in none
};
// Every (row, band) that has tables, in grid order.
std::vector<CellAnswer> AnswerCells(const std::vector<const Group*>& groups);

}  // namespace shimmer::experiments::report
