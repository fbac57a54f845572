// The decision rule on synthetic rows whose answer is known by construction:
// a clear winner, a tie inside intervals, a no-op, a steadier but blurrier
// variant, a row dominated by reference noise, a winner that loses energy;
// then the cells: a pick needs half its cell's tables, supersample-N is never
// one, the runner-up is tied unless intervals separate.
#include <gtest/gtest.h>

#include <cmath>

#include "decision_rule.h"
#include "report_document.h"

namespace shimmer::experiments::report {
namespace {

// tv_err, joint error and spatial error with ± half intervals; energy bias
// with its own interval.
struct RowNumbers {
  double tv_err = 1, tv_half = 0.05;
  double joint = 0.1, joint_half = 0.005;
  double spatial = 0.05, spatial_half = 0.003;
  double bias = 0, bias_half = 0.01;
  double floor = 0.01;
  double ref_noise = -1, ref_mean = 1;  // ref_noise < 0: not measured (older stores)
};

JobResult Row(const std::string& scene, const std::string& material, const std::string& camera,
              const std::string& variant, const RowNumbers& n) {
  JobResult r;
  r.job.scene = scene, r.job.material = material, r.job.camera = camera, r.job.variant = variant;
  r.job.derivatives = "quad";
  r.metrics = {{"tv_err", n.tv_err},   {"relmse", n.joint},         {"relmse_spatial", n.spatial},
               {"energy_bias", n.bias}, {"tv_err_floor", n.floor}, {"tv_ratio", 1.0}};
  if (n.ref_noise >= 0) r.metrics["ref_noise"] = n.ref_noise, r.metrics["ref_mean"] = n.ref_mean;
  r.metrics["ci95"] = {{"tv_err", {n.tv_err - n.tv_half, n.tv_err + n.tv_half}},
                       {"relmse", {n.joint - n.joint_half, n.joint + n.joint_half}},
                       {"relmse_spatial", {n.spatial - n.spatial_half, n.spatial + n.spatial_half}},
                       {"energy_bias", {n.bias - n.bias_half, n.bias + n.bias_half}}};
  return r;
}

Evidence Of(const RowNumbers& n) { return EvidenceOf(Row("sphere", "ggx:0.01", "orbit", "v", n)); }

const RowNumbers kNone{};

TEST(DecisionRule, AClearWinnerIsBetter) {
  RowNumbers winner;
  winner.tv_err = 0.2, winner.joint = 0.04, winner.spatial = 0.05;
  EXPECT_EQ(Decide(Of(winner), Of(kNone)), Outcome::kBetter);
}

TEST(DecisionRule, OverlappingIntervalsAreATieNeverAWin) {
  RowNumbers close;
  close.tv_err = 0.92, close.tv_half = 0.05;  // [0.87, 0.97] against none's [0.95, 1.05]
  EXPECT_EQ(Decide(Of(close), Of(kNone)), Outcome::kTied);
  close.tv_half = 0.02;  // [0.90, 0.94]: apart
  EXPECT_EQ(Decide(Of(close), Of(kNone)), Outcome::kBetter);
}

TEST(DecisionRule, AVariantThatChangesNothingHasNoEffect) {
  RowNumbers same = kNone;
  same.tv_err = 1.01, same.tv_half = 0.001, same.joint = 0.1005;
  EXPECT_EQ(Decide(Of(same), Of(kNone)), Outcome::kNoEffect);
  // Steadier by 3 %, intervals apart: an effect.
  same.tv_err = 0.97, same.joint = 0.097;
  RowNumbers tight = kNone;
  tight.tv_half = 0.001;
  EXPECT_EQ(Decide(Of(same), Of(tight)), Outcome::kBetter);
}

TEST(DecisionRule, SteadierButBlurrierIsNotBetter) {
  RowNumbers blur;
  blur.tv_err = 0.05, blur.spatial = 0.5, blur.spatial_half = 0.05;  // 10x none's spatial error
  EXPECT_EQ(Decide(Of(blur), Of(kNone)), Outcome::kBlurrier);
  // Within the tolerance (1.5x, with intervals) it is better.
  blur.spatial = 0.07, blur.spatial_half = 0.01;  // lower end 0.06 <= 1.5 x 0.053
  EXPECT_EQ(Decide(Of(blur), Of(kNone)), Outcome::kBetter);
  blur.spatial = 0.1, blur.spatial_half = 0.01;  // lower end 0.09 > 0.0795
  EXPECT_EQ(Decide(Of(blur), Of(kNone)), Outcome::kBlurrier);
}

TEST(DecisionRule, AWinnerThatLosesEnergyIsNotBetter) {
  RowNumbers dim;
  dim.tv_err = 0.2, dim.bias = -0.3, dim.bias_half = 0.05;  // [-0.35, -0.25] misses ±0.10
  EXPECT_EQ(Decide(Of(dim), Of(kNone)), Outcome::kLosesEnergy);
  dim.bias = -0.12, dim.bias_half = 0.03;  // [-0.15, -0.09] meets it
  EXPECT_EQ(Decide(Of(dim), Of(kNone)), Outcome::kBetter);
}

TEST(DecisionRule, AGlintFilterThatRendersNoGlintsIsNotBetter) {
  RowNumbers smooth;
  smooth.tv_err = 0.1;
  JobResult r = Row("glint-plane", "glints:0.3", "orbit", "glints-zk16", smooth);
  r.metrics["sparkles"] = {{"mean_count_ratio", 0.0}};
  EXPECT_EQ(Decide(EvidenceOf(r), Of(kNone)), Outcome::kLosesGlints);
  r.metrics["sparkles"]["mean_count_ratio"] = 2.5;  // glitter where the reference has none
  EXPECT_EQ(Decide(EvidenceOf(r), Of(kNone)), Outcome::kLosesGlints);
  r.metrics["sparkles"]["mean_count_ratio"] = 0.8;
  EXPECT_EQ(Decide(EvidenceOf(r), Of(kNone)), Outcome::kBetter);
}

// The sparkles' count variance (tolerance squared: it scales as the count's
// square) and their lifetime weigh in too; glints-smooth, D_g itself, is the
// smooth limit whatever its numbers.
TEST(DecisionRule, GlintVerdictsWeighCountVarianceAndLifetimeAndNameTheSmoothLimit) {
  RowNumbers steady;
  steady.tv_err = 0.1;
  JobResult r = Row("glint-plane", "glints:0.3", "orbit", "glints-zk16", steady);
  r.metrics["sparkles"] = {{"mean_count_ratio", 0.9}, {"count_variance_ratio", 0.3}, {"lifetime_ratio", 1.1}};
  EXPECT_EQ(Decide(EvidenceOf(r), Of(kNone)), Outcome::kBetter);  // 0.3 is inside [1/4, 4]
  r.metrics["sparkles"]["count_variance_ratio"] = 0.2;             // the glitter's contrast is gone
  EXPECT_EQ(Decide(EvidenceOf(r), Of(kNone)), Outcome::kLosesGlints);
  r.metrics["sparkles"]["count_variance_ratio"] = 1.0;
  r.metrics["sparkles"]["lifetime_ratio"] = 0.4;  // sparkles that twinkle out
  EXPECT_EQ(Decide(EvidenceOf(r), Of(kNone)), Outcome::kLosesGlints);
  r.metrics["sparkles"]["lifetime_ratio"] = nullptr;  // undefined: passes
  EXPECT_EQ(Decide(EvidenceOf(r), Of(kNone)), Outcome::kBetter);
  JobResult smooth = Row("glint-plane", "glints:0.3", "orbit", "glints-smooth", steady);
  smooth.metrics["sparkles"] = {{"mean_count_ratio", 1.0}};
  EXPECT_EQ(Decide(EvidenceOf(smooth), Of(kNone)), Outcome::kSmoothLimit);
  EXPECT_EQ(OutcomeText(Outcome::kSmoothLimit), "smooth limit (no glints)");
}

// On a glint material the spatial error compares two microstructures (each
// model draws its own, `none` draws the reference's), not a blur: a model
// ten times `none`'s spatial error that keeps the glints is better there,
// and the same numbers on a smooth material are blurrier.
TEST(DecisionRule, OnAGlintMaterialTheSparklesJudgeInsteadOfTheSpatialError) {
  RowNumbers own;
  own.tv_err = 0.1, own.spatial = 0.5, own.spatial_half = 0.05;  // 10x none's
  JobResult glint = Row("glint-plane", "glints:0.3", "orbit", "glints-zk16-counting", own);
  glint.metrics["sparkles"] = {{"reference", {{"mean_count", 300.0}}},
                               {"mean_count_ratio", 0.95},
                               {"count_variance_ratio", 1.1},
                               {"lifetime_ratio", 1.0}};
  EXPECT_TRUE(EvidenceOf(glint).glint);
  EXPECT_EQ(Decide(EvidenceOf(glint), Of(kNone)), Outcome::kBetter);
  glint.metrics["sparkles"]["mean_count_ratio"] = 0.3;  // the glitter is gone: no blur test needed to say so
  EXPECT_EQ(Decide(EvidenceOf(glint), Of(kNone)), Outcome::kLosesGlints);
  EXPECT_FALSE(Of(own).glint);
  EXPECT_EQ(Decide(Of(own), Of(kNone)), Outcome::kBlurrier);
}

TEST(DecisionRule, ATieDominatedByReferenceNoiseIsUnresolved) {
  RowNumbers noisy;
  noisy.tv_err = 0.95, noisy.floor = 0.9;
  EXPECT_EQ(Decide(Of(noisy), Of(kNone)), Outcome::kUnresolved);
  // The same tie with a quiet reference is a tie.
  noisy.floor = 0.1;
  EXPECT_EQ(Decide(Of(noisy), Of(kNone)), Outcome::kTied);
  // A noisy row that is steadier beyond the noise (intervals apart) is still better.
  noisy.tv_err = 0.3, noisy.floor = 0.9;
  EXPECT_EQ(Decide(Of(noisy), Of(kNone)), Outcome::kBetter);
}

TEST(DecisionRule, ATieUnderNoiseTooFaintToSeeIsATie) {
  // The reference's noise explains 90 % of tv_err, as above, but its
  // contrast is sqrt(1e-6) / 0.5 = 0.2 %: no visible flicker hides under it.
  RowNumbers faint;
  faint.tv_err = 0.95, faint.floor = 0.9, faint.ref_noise = 1e-6, faint.ref_mean = 0.5;
  RowNumbers none = kNone;
  none.ref_noise = 1e-6, none.ref_mean = 0.5;
  EXPECT_TRUE(NoiseBelowVisibility(Of(faint), Of(none)));
  EXPECT_EQ(Decide(Of(faint), Of(none)), Outcome::kTied);
  // A contrast of 2 %: a flicker could hide under it.
  faint.ref_noise = none.ref_noise = 1e-4;
  EXPECT_FALSE(NoiseBelowVisibility(Of(faint), Of(none)));
  EXPECT_EQ(Decide(Of(faint), Of(none)), Outcome::kUnresolved);
  // Just above the limit (1.1 %).
  faint.ref_noise = none.ref_noise = std::pow(1.1 * kVisibleContrast * 0.5, 2);
  EXPECT_EQ(Decide(Of(faint), Of(none)), Outcome::kUnresolved);
  // Unknown contrast (a store measured before ref_noise): unresolved, as before.
  faint.ref_noise = -1;
  EXPECT_EQ(Decide(Of(faint), Of(kNone)), Outcome::kUnresolved);
}

// Bootstrap draws whose replicates share a common part (the resampling of
// what both rows see: the same tiles, frames and reference) and carry a
// small part of their own: paired, the common part cancels.
std::shared_ptr<const metrics::BootstrapDraws> Draws(double value, double own, std::uint64_t key,
                                                     std::uint64_t seed) {
  auto draws = std::make_shared<metrics::BootstrapDraws>();
  draws->key = key;
  for (int i = 0; i < 1000; ++i) {
    const double common = 0.3 * std::sin(0.7 * i) * std::cos(1.3 * i);  // the same in every row
    const double mine = own * std::sin(double(seed) * 12.9898 + 78.233 * i);
    const float x = float(value + common + mine);
    for (metrics::Replicates* r : {&draws->tv_err, &draws->relmse}) {
      r->joint.push_back(x), r->tiles_only.push_back(x), r->blocks_only.push_back(x);
    }
  }
  return draws;
}

JobResult PairedRow(const std::string& variant, const RowNumbers& n, double own, std::uint64_t key,
                    std::uint64_t seed) {
  JobResult r = Row("sphere", "ggx:0.01", "orbit", variant, n);
  r.draws = Draws(n.tv_err, own, key, seed);
  r.reference_id = "shot-reference";
  r.metrics["frames"] = 48, r.metrics["pixels"] = 10, r.metrics["tv_test"] = 1.0;
  return r;
}

TEST(DecisionRule, RowsOnTheSameDrawsCompareTheirDifference) {
  // Intervals of ±0.5 overlap (0.8 against 1): unpaired, a tie.
  RowNumbers v = kNone, n = kNone;
  v.tv_err = 0.8, v.tv_half = n.tv_half = 0.5;
  EXPECT_EQ(Decide(Of(v), Of(n)), Outcome::kTied);
  // Paired, the common spread cancels: the difference's interval is about
  // ±0.02 around -0.2.
  const JobResult a = PairedRow("v", v, 0.005, 7, 1), b = PairedRow("none", n, 0.005, 7, 2);
  const auto d = PairedTvErr(EvidenceOf(a), EvidenceOf(b));
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->difference, -0.2, 1e-12);
  EXPECT_LT(d->ci.hi, -0.15);
  EXPECT_GT(d->ci.lo, -0.25);
  EXPECT_EQ(Decide(EvidenceOf(a), EvidenceOf(b)), Outcome::kBetter);
  // Other draws (another region): unpaired again.
  const JobResult other = PairedRow("none", n, 0.005, 8, 2);
  EXPECT_FALSE(PairedTvErr(EvidenceOf(a), EvidenceOf(other)));
  EXPECT_EQ(Decide(EvidenceOf(a), EvidenceOf(other)), Outcome::kTied);
  // The same draws against another reference (an external sequence's own):
  // their noises differ and do not cancel, so unpaired again.
  JobResult external = PairedRow("none", n, 0.005, 7, 2);
  external.reference_id = "engine-reference";
  EXPECT_FALSE(PairedTvErr(EvidenceOf(a), EvidenceOf(external)));
}

TEST(DecisionRule, APairedTieIsUnresolvedOnlyWhereTheNoiseCrossTermDominatesIt) {
  RowNumbers v = kNone, n = kNone;
  v.tv_err = 0.97;  // 3 % apart: not "no effect"
  v.floor = n.floor = 0.99;  // unpaired, the noise is 99 % of each tv_err
  v.ref_noise = n.ref_noise = 1e-6, v.ref_mean = n.ref_mean = 1e-3;  // contrast 100 %: visible
  // A paired tie whose own spread (about ±0.07) dwarfs the cross term of a faint
  // F = 1e-6 (sigma = 2 sqrt(F (1 + 1)^2 / (47 * 10)) = 1.8e-4): a tie, not unresolved.
  JobResult a = PairedRow("v", v, 0.1, 7, 1), b = PairedRow("none", n, 0.1, 7, 2);
  EXPECT_LT(NoiseShare(EvidenceOf(a), EvidenceOf(b)), 0.1);
  EXPECT_EQ(Decide(EvidenceOf(a), EvidenceOf(b)), Outcome::kTied);
  // F = 1 (sigma 0.18, 1.96 sigma = 0.36 against the replicates' 0.07): the
  // cross term is the comparison's uncertainty, and the tie is unresolved.
  a.metrics["ref_noise"] = b.metrics["ref_noise"] = 1.0;
  EXPECT_GT(NoiseShare(EvidenceOf(a), EvidenceOf(b)), 0.9);
  EXPECT_EQ(Decide(EvidenceOf(a), EvidenceOf(b)), Outcome::kUnresolved);
}

TEST(DecisionRule, LessSteadyAndUnknown) {
  RowNumbers worse;
  worse.tv_err = 3;
  EXPECT_EQ(Decide(Of(worse), Of(kNone)), Outcome::kLessSteady);
  JobResult bare = Row("sphere", "ggx:0.01", "orbit", "v", kNone);
  bare.metrics.erase("ci95");
  EXPECT_EQ(Decide(EvidenceOf(bare), Of(kNone)), Outcome::kUnknown);
}

TEST(DecisionRule, SeparateRanksOnlyApartIntervals) {
  EXPECT_EQ(Separate({1, 2}, {3, 4}), Verdict::kBetter);
  EXPECT_EQ(Separate({3, 4}, {1, 2}), Verdict::kWorse);
  EXPECT_EQ(Separate({1, 3}, {2, 4}), Verdict::kIndistinguishable);
  EXPECT_EQ(Separate({1, 2}, {}), Verdict::kUnknown);
}

// One cell (small curved, α ≤ 0.02) of four tables: `a` better in 3 of 4
// with the lowest joint error, `b` better in all 4 but with a higher joint
// error, `c` better in 1 of 4 only, `blur` steadiest but blurrier, and
// supersample-4 best of all yet never a pick.
std::vector<JobResult> CellRows(double b_joint) {
  std::vector<JobResult> rows;
  int table = 0;
  for (const char* material : {"ggx:0.01", "ggx:0.02"})
    for (const char* camera : {"orbit", "dolly"}) {
      auto add = [&](const char* v, RowNumbers n) { rows.push_back(Row("sphere", material, camera, v, n)); };
      add("none", kNone);
      RowNumbers a;
      a.tv_err = table < 3 ? 0.3 : 0.98, a.joint = 0.03;
      add("a", a);
      RowNumbers b;
      b.tv_err = 0.4, b.joint = b_joint;
      add("b", b);
      RowNumbers c;
      c.tv_err = table == 0 ? 0.3 : 1.0, c.joint = 0.01;
      add("c", c);
      RowNumbers blur;
      blur.tv_err = 0.01, blur.joint = 0.02, blur.spatial = 1.0;
      add("blur", blur);
      RowNumbers ss;
      ss.tv_err = 0.05, ss.joint = 0.005;
      add("supersample-4", ss);
      ++table;
    }
  return rows;
}

std::vector<const Group*> Pointers(const std::vector<Group>& groups) {
  std::vector<const Group*> out;
  for (const Group& g : groups) out.push_back(&g);
  return out;
}

TEST(DecisionRuleCells, ThePickIsBetterInHalfTheTablesWithTheLowestJointError) {
  const std::vector<JobResult> rows = CellRows(0.05);
  const std::vector<Group> groups = GroupRows(rows);
  const std::vector<CellAnswer> cells = AnswerCells(Pointers(groups));
  ASSERT_EQ(cells.size(), 1u);
  const CellAnswer& cell = cells[0];
  EXPECT_EQ(cell.row, "small curved");
  EXPECT_EQ(cell.band, "α ≤ 0.02");
  EXPECT_EQ(cell.tables, 4);
  ASSERT_NE(cell.pick, nullptr);
  EXPECT_EQ(cell.pick->label, "a");  // 3/4, joint ratio 0.3; `c` has 0.1 but 1/4
  EXPECT_EQ(cell.pick->better, 3);
  ASSERT_NE(cell.runner_up, nullptr);
  EXPECT_EQ(cell.runner_up->label, "b");
  // a's joint error [0.025, 0.035] lies below b's [0.045, 0.055] in every table.
  EXPECT_EQ(cell.ahead, 4);
  EXPECT_TRUE(cell.pick_ahead);
  for (const CellCandidate& c : cell.candidates) {
    if (c.label == "blur") {
      EXPECT_EQ(c.better, 0);
    }
    if (c.label == "supersample-4") {
      EXPECT_EQ(c.better, 4);
    }
  }
  // b's joint error overlapping a's: the two are tied.
  const std::vector<JobResult> close = CellRows(0.034);
  const std::vector<Group> close_groups = GroupRows(close);
  const std::vector<CellAnswer> tied = AnswerCells(Pointers(close_groups));
  ASSERT_NE(tied[0].pick, nullptr);
  EXPECT_EQ(tied[0].pick->label, "a");
  EXPECT_FALSE(tied[0].pick_ahead);
  EXPECT_EQ(tied[0].tied, 4);
  const std::string md = ToMarkdown(BuildDocument(close_groups, "t", close.size()));
  EXPECT_NE(md.find("| small curved | **`a`** 3/4 (tied with `b`) |"), std::string::npos) << md;
}

TEST(DecisionRuleCells, NothingBetterOftenEnoughKeepsNone) {
  std::vector<JobResult> rows;
  int table = 0;
  for (const char* camera : {"orbit", "dolly", "pan"}) {
    rows.push_back(Row("wires", "ggx:0.5", camera, "none", kNone));
    RowNumbers once;
    once.tv_err = table == 0 ? 0.5 : 0.99;
    rows.push_back(Row("wires", "ggx:0.5", camera, "tk21", once));
    RowNumbers same = kNone;
    rows.push_back(Row("wires", "ggx:0.5", camera, "vlachos15", same));  // no effect anywhere
    ++table;
  }
  const std::vector<Group> groups = GroupRows(rows);
  const std::vector<CellAnswer> cells = AnswerCells(Pointers(groups));
  ASSERT_EQ(cells.size(), 1u);
  EXPECT_EQ(cells[0].row, "thin");
  EXPECT_EQ(cells[0].pick, nullptr);
  for (const CellCandidate& c : cells[0].candidates)
    if (c.label == "vlachos15") {
      EXPECT_EQ(c.no_effect, 3);
    }
  const std::string md = ToMarkdown(BuildDocument(groups, "t", rows.size()));
  EXPECT_NE(md.find("| thin | keep `none` (best: `tk21` 1/3) |"), std::string::npos) << md;
  // The answer opens the report: grid, how to read it, then the contents.
  EXPECT_LT(md.find("## Answer"), md.find("**How to read it.**"));
  EXPECT_LT(md.find("**How to read it.**"), md.find("## Contents"));
  EXPECT_LT(md.find("## Contents"), md.find("## Overview"));
  EXPECT_NE(md.find("- [Method](#method)"), std::string::npos) << md;
}

TEST(DecisionRuleCells, NormalMappedSgLitAndGlintMaterialsAreRowsOfTheirOwn) {
  std::vector<JobResult> rows;
  for (const char* scene : {"nm-plane", "sg-plane", "glint-plane", "bumpy-plane"}) {
    const std::string material = std::string(scene) == "glint-plane" ? "glints:0.3,local=0.03,density=1e4" : "ggx:0.05";
    rows.push_back(Row(scene, material, "orbit", "none", kNone));
  }
  const std::vector<Group> groups = GroupRows(rows);
  std::set<std::string> names;
  for (const Group& g : groups) names.insert(CellRowOf(g));
  EXPECT_EQ(names, (std::set<std::string>{"normal-mapped", "SG-lit", "glints", "flat with normal detail"}));
}

}  // namespace
}  // namespace shimmer::experiments::report
