// The report from synthetic rows with known numbers: the overview's
// statistics, the recommendation rule, interval verdicts, ordering, costs per
// device, the CSV and the self-contained HTML page.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "job_results.h"
#include "decision_rule.h"
#include "report_document.h"
#include "report_parts.h"
#include "shimmer/experiments/csv.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/report.h"
#include "shimmer/shading/shading.h"
#include "temp_dir.h"

namespace shimmer::experiments {
namespace {

namespace fs = std::filesystem;
using namespace report;

using shimmer::testing::TempDir;
using testing::MakeResult;

std::string ReadText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A row of shot (scene, material) with known tv_err and energy bias; `half`
// > 0 gives tv_err a 95 % interval of ± half.
JobResult Row(const std::string& scene, const std::string& material, const std::string& variant, double tv_err,
              double bias, double half = 0) {
  JobResult r;
  r.job.scene = scene;
  r.job.material = material;
  r.job.camera = "orbit";
  r.job.variant = variant;
  r.job.derivatives = "quad";
  r.job.reference.spp = 4;
  r.job.reference.tolerance = 0;
  r.metrics = {{"tv_err", tv_err}, {"energy_bias", bias}, {"tv_ratio", 1.0}, {"relmse", 0.1}};
  if (half > 0) r.metrics["ci95"] = {{"tv_err", {tv_err - half, tv_err + half}}};
  r.gpu_ms_per_frame = 1;
  r.device = "dev";
  return r;
}

void Bench(JobResult& r, double ratio, const std::string& device = "bench-gpu") {
  BenchmarkCost c;
  c.variant = r.job.variant, c.device = device, c.ratio_to_none = ratio;
  c.median_ms = 2 * ratio, c.min_ms = 1.9 * ratio, c.max_ms = 2.2 * ratio, c.width = c.height = 512;
  r.cost = c;
}

std::vector<const Group*> Pointers(const std::vector<Group>& groups) {
  std::vector<const Group*> out;
  for (const Group& g : groups) out.push_back(&g);
  return out;
}

const VariantSummary& Find(const std::vector<VariantSummary>& all, const std::string& label) {
  for (const VariantSummary& v : all)
    if (v.label == label) return v;
  throw std::runtime_error("no summary of " + label);
}

// A store run with two versions of the code: the report keeps the current
// rows, an external sequence's as any other's (its id holds the metrics
// code's version), and says how many it left out.
TEST(ReportRows, RowsOfOlderCodeAreLeftOutWithANote) {
  std::vector<JobResult> rows;
  for (const char* id : {"old", "new-1", "new-2"}) {
    rows.push_back(MakeResult("tk19", 1, 2));
    rows.back().id = id;
  }
  for (const char* id : {"ext-old", "ext"}) {
    rows.push_back(MakeResult("none", 1, 2));
    rows.back().id = id;
    rows.back().job.external = ExternalFrames{};
  }
  std::string note;
  const auto kept = CurrentRows(rows, {"new-1", "new-2", "ext"}, &note);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0].id, "new-1");
  EXPECT_EQ(kept[2].id, "ext");
  EXPECT_NE(note.find("holds 2 rows made by other code"), std::string::npos) << note;
  // None of them current: all are shown, and the note says so.
  note.clear();
  EXPECT_EQ(CurrentRows(rows, {"other"}, &note).size(), 5u);
  EXPECT_NE(note.find("no row of the store"), std::string::npos) << note;
  // All current: nothing left out, no note.
  note.clear();
  EXPECT_EQ(CurrentRows({rows[1], rows[2]}, {"new-1", "new-2"}, &note).size(), 2u);
  EXPECT_TRUE(note.empty());
}

TEST(ReportStatistics, QuartilesInterpolateBetweenOrderStatistics) {
  const Quartiles q = QuartilesOf({3, 1, std::nan(""), 2});
  EXPECT_EQ(q.n, 3);
  EXPECT_DOUBLE_EQ(q.median, 2);
  EXPECT_DOUBLE_EQ(q.q1, 1.5);
  EXPECT_DOUBLE_EQ(q.q3, 2.5);
  EXPECT_TRUE(std::isnan(QuartilesOf({}).median));
}

TEST(ReportStatistics, AlphaAndClasses) {
  EXPECT_DOUBLE_EQ(AlphaOf("ggx:0.02"), 0.02);
  EXPECT_NEAR(AlphaOf("ggx:0.1,0.02"), std::sqrt(0.1 * 0.02), 1e-12);
  EXPECT_TRUE(std::isnan(AlphaOf("not a material")));
  EXPECT_EQ(RoughnessClass(0.02), "α ≤ 0.02");
  EXPECT_EQ(RoughnessClass(0.05), "0.02 < α ≤ 0.1");
  EXPECT_EQ(RoughnessClass(0.3), "0.1 < α ≤ 0.3");
  EXPECT_EQ(RoughnessClass(0.5), "α > 0.3");
  EXPECT_EQ(GeometryClass("sphere-field"), "small curved");
  EXPECT_EQ(GeometryClass("wires"), "thin");
  EXPECT_EQ(GeometryClass("bumpy-plane"), "flat with normal detail");
  EXPECT_EQ(GeometryClass("my.json"), "other");
}

TEST(ReportStatistics, IntervalsCallBetterOnlyWhenSeparate) {
  JobResult r = Row("sphere", "ggx:0.02", "tk21", 0.5, 0, 0.1);
  EXPECT_DOUBLE_EQ(Ci95(r, "tv_err").lo, 0.4);
  EXPECT_FALSE(Ci95(r, "relmse").Known());  // absent: no interval, not an error
}

// Four shots; tk21's ratios 0.1, 0.2, 0.4, 0.8 by hand: median 0.3, quartiles
// 0.175 and 0.5; biases 0.05, -0.2, 0.1, 0 → 3/4 within 0.10; cost ratios
// 1.2, 1.4, 1.0, 1.6 → median 1.3.
TEST(ReportOverview, LeaderboardMediansQuartilesAndShares) {
  std::vector<JobResult> rows;
  const double ratio[] = {0.1, 0.2, 0.4, 0.8}, bias[] = {0.05, -0.2, 0.1, 0}, cost[] = {1.2, 1.4, 1.0, 1.6};
  const char* materials[] = {"ggx:0.01", "ggx:0.05", "ggx:0.2", "ggx:0.5"};
  for (int i = 0; i < 4; ++i) {
    rows.push_back(Row("sphere", materials[i], "none", 2.0, 0.01));
    Bench(rows.back(), 1.0);
    rows.push_back(Row("sphere", materials[i], "tk21", 2.0 * ratio[i], bias[i]));
    Bench(rows.back(), cost[i]);
    rows.push_back(Row("sphere", materials[i], "vlachos15", 4.0, 0));
  }
  const std::vector<Group> groups = GroupRows(rows);
  ASSERT_EQ(groups.size(), 4u);
  const auto summaries = Summarise(Pointers(groups));
  ASSERT_EQ(summaries.size(), 3u);
  EXPECT_EQ(summaries[0].label, "tk21");  // sorted by median ratio
  EXPECT_EQ(summaries[1].label, "none");
  EXPECT_EQ(summaries[2].label, "vlachos15");
  const VariantSummary& tk21 = summaries[0];
  EXPECT_EQ(tk21.ratio.n, 4);
  EXPECT_NEAR(tk21.ratio.median, 0.3, 1e-12);
  EXPECT_NEAR(tk21.ratio.q1, 0.175, 1e-12);
  EXPECT_NEAR(tk21.ratio.q3, 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(tk21.energy_share, 0.75);
  ASSERT_EQ(tk21.cost_ratio.count("bench-gpu"), 1u);
  EXPECT_NEAR(tk21.cost_ratio.at("bench-gpu").median, 1.3, 1e-12);
  EXPECT_TRUE(Find(summaries, "vlachos15").cost_ratio.empty());
  const std::string md = ToMarkdown(BuildDocument(groups, "t", rows.size()));
  // The class's leaderboard: no intervals in these rows, so nothing is called better.
  EXPECT_NE(md.find("#### small curved (4 tables)"), std::string::npos) << md;
  EXPECT_NE(md.find("| `tk21` | 4 | 0/4 | 1 (IQR 1–1) | 0.3 (IQR 0.175–0.5) | 3/4 | 1.30× |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `vlachos15` | 4 | 0/4 | 1 (IQR 1–1) | 2 (IQR 2–2) | 4/4 | n/a |"), std::string::npos) << md;
  // The answer comes first, the overview after it, the per-shot tables last.
  EXPECT_LT(md.find("## Answer"), md.find("## Overview"));
  EXPECT_LT(md.find("### Leaderboards by class"), md.find("## Shots"));
}

// SG-lit shots run their own variants: they form their own class and stay
// out of the delta-lit roughness and geometry classes, where they would be
// tables the delta-lit filters were never measured in.
TEST(ReportOverview, SgLitShotsAreTheirOwnClass) {
  std::vector<JobResult> rows;
  for (const char* camera : {"orbit", "dolly"}) {
    auto add = [&](const char* scene, const char* v, double err) {
      rows.push_back(Row(scene, "ggx:0.05", v, err, 0.0, 0.05));
      rows.back().job.camera = camera;
    };
    add("sphere", "none", 1.0);
    add("sphere", "unity-hdrp", 0.3);
    add("sg-plane", "none", 1.0);
    add("sg-plane", "asg-warp", 2.0);
    add("sg-plane", "tk21", 0.5);
  }
  const std::vector<Group> groups = GroupRows(rows);
  const auto cells = AnswerCells(Pointers(groups));
  ASSERT_EQ(cells.size(), 2u);
  EXPECT_EQ(cells[0].row, "small curved");
  EXPECT_EQ(cells[0].tables, 2);  // sphere only
  ASSERT_NE(cells[0].pick, nullptr);
  EXPECT_EQ(cells[0].pick->label, "unity-hdrp");
  EXPECT_EQ(cells[1].row, "SG-lit");
  EXPECT_EQ(cells[1].tables, 2);
  ASSERT_NE(cells[1].pick, nullptr);
  EXPECT_EQ(cells[1].pick->label, "tk21");
}

// A scene file's geometry_class (stored with its rows' traits) is a row of
// the answer of its own, placed before "other"; a mesh scene without one is
// "mesh".
TEST(ReportOverview, DeclaredGeometryClassesAreRowsOfTheirOwn) {
  std::vector<JobResult> rows;
  for (const char* camera : {"orbit", "dolly"}) {
    auto add = [&](const char* scene, const char* v, double err, nlohmann::json traits) {
      rows.push_back(Row(scene, "ggx:0.05", v, err, 0.0, 0.05));
      rows.back().job.camera = camera;
      if (!traits.is_null()) rows.back().sources = {{"scene", traits}};
    };
    const nlohmann::json lowpoly = {{"sg_light", false}, {"normal_maps", false}, {"sg_sharpness", 0},
                                    {"meshes", true}, {"geometry_class", "low-poly mesh"}};
    const nlohmann::json mesh = {{"sg_light", false}, {"normal_maps", false}, {"sg_sharpness", 0}, {"meshes", true}};
    add("sphere", "none", 1.0, nullptr);
    add("sphere", "tk19", 0.5, nullptr);
    add("torus.json", "none", 1.0, lowpoly);
    add("torus.json", "tk19", 0.4, lowpoly);
    add("asset.json", "none", 1.0, mesh);
    add("asset.json", "tk19", 0.4, mesh);
    add("my.json", "none", 1.0, nullptr);
    add("my.json", "tk19", 0.4, nullptr);
  }
  const std::vector<Group> groups = GroupRows(rows);
  const auto cells = AnswerCells(Pointers(groups));
  std::vector<std::string> order;
  for (const CellAnswer& c : cells) order.push_back(c.row);
  EXPECT_EQ(order, (std::vector<std::string>{"small curved", "low-poly mesh", "mesh", "other"}));
  EXPECT_EQ(CellRowsInOrder({"glints", "zz", "other", "aa", "thin"}),
            (std::vector<std::string>{"thin", "aa", "zz", "other", "glints"}));
}

// The paper's ordering: the first form wholly above all others, the last
// wholly above none.
TEST(ReportBeyond, Fig1OrderingNeedsSeparateIntervals) {
  const Interval k16{10, 20}, mid{1, 2}, tk19{0.5, 1.5}, low{0.1, 0.4};
  EXPECT_TRUE(Fig1OrderingHolds({k16, mid, tk19}, 0, 2));
  EXPECT_FALSE(Fig1OrderingHolds({k16, mid, low, tk19}, 0, 3));  // tk19 wholly above `low`
  EXPECT_FALSE(Fig1OrderingHolds({Interval{1.9, 20}, mid, tk19}, 0, 2));  // k16 overlaps `mid`
  EXPECT_TRUE(Fig1OrderingHolds({k16, mid, Interval{0.2, 1.5}}, 0, 2));
  EXPECT_FALSE(Fig1OrderingHolds({k16, Interval{}, tk19}, 0, 2));        // unknown: not judged to hold
}

// Normal-mapped shots run the normal-map filters: their own class, and a
// section with each filter's stored bytes per texel beside its error.
TEST(ReportOverview, NormalMappedShotsAreTheirOwnClassWithTheirMemory) {
  std::vector<JobResult> rows;
  for (const char* camera : {"orbit", "dolly"}) {
    auto add = [&](const char* scene, const char* v, double err) {
      rows.push_back(Row(scene, "ggx:0.05", v, err, 0.0, 0.05));
      rows.back().job.camera = camera;
    };
    add("sphere", "none", 1.0);
    add("sphere", "tk19", 0.5);
    add("nm-plane", "none", 1.0);
    add("nm-plane", "lean", 0.2);
    add("nm-plane", "toksvig-map", 0.3);
    add("nm-plane", "tk19+clean", 0.25);
  }
  const std::vector<Group> groups = GroupRows(rows);
  const auto cells = AnswerCells(Pointers(groups));
  ASSERT_EQ(cells.size(), 2u);
  EXPECT_EQ(cells[0].row, "small curved");
  EXPECT_EQ(cells[0].tables, 2);  // sphere only
  EXPECT_EQ(cells[1].row, "normal-mapped");
  EXPECT_EQ(cells[1].tables, 2);
  ASSERT_NE(cells[1].pick, nullptr);
  EXPECT_EQ(cells[1].pick->better, 2);
  const std::string md = ToMarkdown(BuildDocument(groups, "t", rows.size()));
  const std::size_t at = md.find(std::string("## ") + kNormalMapMemoryHeading);
  ASSERT_NE(at, std::string::npos) << md;
  const std::string section = md.substr(at, md.find("\n## ", at + 1) - at);
  EXPECT_NE(section.find("| `lean` | 2 | 0.2 (IQR 0.2–0.2) | +0.000 | B and M: two RGBA16F textures | 16 |"),
            std::string::npos)
      << section;
  EXPECT_NE(section.find("| `toksvig-map` | 2 | 0.3"), std::string::npos) << section;
  EXPECT_NE(section.find("| `tk19+clean` | 2 | 0.25 (IQR 0.25–0.25) | +0.000 | B and M_z: one RGBA16F texture | 8 |"),
            std::string::npos)
      << section;
  EXPECT_EQ(section.find("`tk19` |"), std::string::npos);  // not a normal-mapped shot's row
}

// The overview's "Beyond the papers" part from rows with known numbers.
std::string BeyondSection(const std::vector<JobResult>& rows, const std::vector<JointFit>& fits = {}) {
  const std::vector<Group> groups = GroupRows(rows);
  const std::string md = ToMarkdown(BuildDocument(groups, "t", rows.size(), nullptr, nullptr, fits));
  const std::size_t at = md.find(std::string("### ") + kBeyondHeading);
  if (at == std::string::npos) return "";
  return md.substr(at, md.find("\n## ", at + 1) - at);
}

void WithIntervals(JobResult& r, double tv_half, double bias_half) {
  const double tv = r.metrics["tv_err"], bias = r.metrics["energy_bias"];
  r.metrics["ci95"] = {{"tv_err", {tv - tv_half, tv + tv_half}}, {"energy_bias", {bias - bias_half, bias + bias_half}}};
}

TEST(ReportBeyond, JacobianAgainstTheCentreFormPerScene) {
  std::vector<JobResult> rows;
  for (const char* camera : {"orbit", "dolly"}) {
    auto add = [&](const char* scene, const char* v, double err, double bias, double bias_half) {
      rows.push_back(Row(scene, "ggx:0.02", v, err, bias));
      rows.back().job.camera = camera;
      WithIntervals(rows.back(), 0.05, bias_half);
    };
    add("sphere-field", "none", 1.0, 0.0, 0.01);
    add("sphere-field", "k16-ggx-rect-stable", 0.3, 0.56, 0.05);
    add("sphere-field", "k16-ggx-rect-jacobian", 0.32, 0.02, 0.05);  // closer to 0, intervals apart
    add("wires", "none", 1.0, 0.0, 0.01);
    add("wires", "k16-ggx-rect-stable", 0.5, -0.10, 0.2);
    add("wires", "k16-ggx-rect-jacobian", 0.9, -0.05, 0.2);  // closer, overlapping; tv_err higher
  }
  const std::string section = BeyondSection(rows);
  ASSERT_FALSE(section.empty());
  EXPECT_NE(section.find("| sphere-field | 2 | +0.560 (+0.560–+0.560) | +0.020 (+0.020–+0.020) | 2 (2 apart) | "
                         "0.3 (0.3–0.3) | 0.32 (0.32–0.32) | 0 / 2 / 0 |"),
            std::string::npos)
      << section;
  EXPECT_NE(section.find("| wires | 2 | -0.100 (-0.100–-0.100) | -0.050 (-0.050–-0.050) | 2 (0 apart) | 0.5 "
                         "(0.5–0.5) | 0.9 (0.9–0.9) | 0 / 0 / 2 |"),
            std::string::npos)
      << section;
  EXPECT_NE(section.find("| **all** | 4 |"), std::string::npos) << section;
  // No TK19 rows and no fits: those parts say what they need.
  EXPECT_NE(section.find("Needs `tk19-forward`"), std::string::npos) << section;
  EXPECT_NE(section.find("--fits"), std::string::npos) << section;
}

TEST(ReportBeyond, Tk19FormsOrderedByRelmsePerSceneAtTheLowestAlpha) {
  std::vector<JobResult> rows;
  struct V {
    const char* variant;
    std::map<std::string, double> params;
    double relmse;
  };
  const V forms[] = {{"none", {}, 6.0},
                     {"k16-beckmann-parallelogram", {{"sigma2", 1.0}}, 400.0},
                     {"k16-beckmann-parallelogram", {}, 150.0},  // the default sigma2 = 0.25
                     {"k16-beckmann-rect", {{"fp_max", 1.0}}, 60.0},
                     {"tk19-forward-rect", {}, 20.0},
                     {"tk19-forward", {}, 10.0}};
  for (const char* material : {"ggx:0.01", "ggx:0.05"})
    for (const V& f : forms) {
      rows.push_back(Row("bumpy-plane", material, f.variant, 1.0, 0.0));
      rows.back().job.params = f.params;
      // At α = 0.05 everything is 10x worse: the part reads the lowest α only,
      // and the largest relmse over all tables finds the other one.
      rows.back().metrics["relmse"] = f.relmse * (std::string(material) == "ggx:0.01" ? 1 : 10);
    }
  const std::string section = BeyondSection(rows);
  EXPECT_NE(section.find("**bumpy-plane, quad**, lowest relmse first: TK19 non-axis-aligned 10 (+0.00) < TK19 "
                         "axis-aligned 20 (+0.00) < K16 axis-aligned 60 (+0.00) < K16 non-axis-aligned, ½U (0.5 px "
                         "filter) 150 (+0.00) < K16 non-axis-aligned, the slide's bare U 400 (+0.00)"),
            std::string::npos)
      << section;
  EXPECT_NE(section.find("| K16 non-axis-aligned, the slide's bare U | `k16-beckmann-parallelogram sigma2=1` | 400 "
                         "(+0.000) | 4000 (bumpy-plane / ggx:0.05 / orbit / quad) |"),
            std::string::npos)
      << section;
}

TEST(ReportBeyond, EngineSettingsFromJointFits) {
  JointFit f;
  f.variant = "unity-hdrp", f.material = "ggx:0.02", f.ndf = "ggx", f.alpha = 0.02;
  f.params = {"sigma2", "kappa"};
  f.search.best = {0.2, 0.09};
  f.defaults = {0.1, 0.04};
  f.validate = {1.0, 0.1, {}};
  f.validate_defaults = {2.0, 0.1, {}};  // apart: fitted better
  f.folds.push_back({"wires", true, {0.3, 0.04}, {3.0, 0.1, {}}, {1.0, 0.1, {}}});
  f.folds.push_back({"wires", false, {0.3, 0.04}, {1.0, 0.5, {}}, {1.2, 0.5, {}}});
  std::vector<JobResult> rows = {Row("sphere", "ggx:0.02", "none", 1.0, 0.0)};
  const std::string section = BeyondSection(rows, {f});
  // HDRP's threshold is the root of kappa: sqrt(0.09) = 0.3.
  EXPECT_NE(section.find("| ggx:0.02 | Unity HDRP (`unity-hdrp`) | screen space variance = 0.2, threshold = 0.3 | "
                         "screen space variance = 0.1, threshold = 0.2 | 1 ± 0.1 (2 ± 0.1) | fitted better |"),
            std::string::npos)
      << section;
  EXPECT_NE(section.find("fitted better in 0, shipped better in 1, tied (intervals overlap) in 0. Fitted on one scene "
                         "alone and measured there under the validation cameras: fitted better in 0, shipped better "
                         "in 0, tied (intervals overlap) in 1."),
            std::string::npos)
      << section;
}

// Glint shots' sparkle statistics: one reference row per shot, then each
// variant's counts and ratios; stores without them have no such section.
TEST(ReportSparkles, ReferenceRowOncePerShotThenEachVariant) {
  std::vector<JobResult> rows;
  const nlohmann::json reference = {{"mean_count", 40.0}, {"count_cv", 0.25}, {"mean_lifetime", 3.5}};
  auto add = [&](const char* variant, double count, double cv, double ratio) {
    rows.push_back(Row("glint-plane", "glints:0.3", variant, 1.0, 0.0));
    rows.back().metrics["sparkles"] = {
        {"threshold", 2.0},
        {"reference", reference},
        {"test", {{"mean_count", count}, {"count_cv", cv}, {"mean_lifetime", 1.5}}},
        {"mean_count_ratio", ratio},
        {"count_variance_ratio", ratio * ratio},
        {"lifetime_ratio", 1.5 / 3.5}};
  };
  add("none", 80.0, 0.9, 2.0);
  add("glints-zk16", 2.0, 0.1, 0.05);
  const std::string md = ToMarkdown(BuildDocument(GroupRows(rows), "t", rows.size()));
  const std::size_t at = md.find(std::string("## ") + kSparklesHeading);
  ASSERT_NE(at, std::string::npos) << md;
  const std::string section = md.substr(at, md.find("\n## ", at + 1) - at);
  EXPECT_NE(section.find("luminance exceeds 2 in a frame"), std::string::npos) << section;
  EXPECT_NE(section.find("| glint-plane / glints:0.3 / orbit | reference | 40.0 | 0.250 | 3.50 |  |  |  |  |"),
            std::string::npos)
      << section;
  EXPECT_NE(section.find("| glint-plane / glints:0.3 / orbit | `glints-zk16` | 2.0 | 0.100 | 1.50 | 0.05 | 0.0025 | "
                         "0.429 |"),
            std::string::npos)
      << section;
  std::size_t references = 0;
  for (std::size_t p = section.find("| reference |"); p != std::string::npos; p = section.find("| reference |", p + 1))
    ++references;
  EXPECT_EQ(references, 1u);
  // Without sparkle statistics there is no section.
  rows = {Row("sphere", "ggx:0.05", "none", 1.0, 0.0)};
  EXPECT_EQ(ToMarkdown(BuildDocument(GroupRows(rows), "t", 1)).find(kSparklesHeading), std::string::npos);
}

// Each shot's verdict column follows the decision rule against its `none`:
// separate intervals make `better`, overlapping ones `≈ none`.
TEST(ReportTables, VerdictColumnFollowsTheDecisionRule) {
  std::vector<JobResult> rows;
  for (auto [v, err] : {std::pair<const char*, double>{"none", 1.0}, {"tk21", 0.20}, {"toksvig-quad", 0.98}})
    rows.push_back(Row("sphere", "ggx:0.01", v, err, 0.0, 0.04));
  const std::vector<Group> groups = GroupRows(rows);
  const std::string md = ToMarkdown(BuildDocument(groups, "t", rows.size()));
  // [0.16, 0.24] over [0.96, 1.04]: the ratio's interval is [0.154, 0.25].
  EXPECT_NE(md.find("| `tk21` | 0.1 | 0.2 [0.154, 0.25] | 1 | +0.000 | n/a | n/a | **better**, lowest joint error |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| `toksvig-quad` | 0.1 | 0.98 [0.904, 1.06] | 1 | +0.000 | n/a | n/a | ≈ none |"), std::string::npos)
      << md;
  EXPECT_NE(md.find("| `none` | 0.1 | 1 [0.923, 1.08] | 1 | +0.000 | n/a | n/a | baseline |"), std::string::npos) << md;
}

// The reference-noise section counts each row once by the decision rule:
// unresolved ties (noise over half of the comparison and visible), ties
// under noise too faint to see, and the shots that hold the unresolved.
TEST(ReportTables, ReferenceNoiseSectionCountsRowsByTheRule) {
  std::vector<JobResult> rows;
  auto add = [&](const char* scene, const char* variant, double tv_err, double noise) {
    JobResult r = Row(scene, "ggx:0.01", variant, tv_err, 0.0, 0.04);
    r.metrics["tv_err_floor"] = 0.9;
    r.metrics["ref_noise"] = noise, r.metrics["ref_mean"] = 0.5;
    rows.push_back(r);
  };
  // Contrast sqrt(1e-2) / 0.5 = 20 %: visible. `a` ties: unresolved; `b` is apart: better.
  add("sphere", "none", 1.0, 1e-2);
  add("sphere", "a", 0.95, 1e-2);
  add("sphere", "b", 0.2, 1e-2);
  // Contrast sqrt(1e-6) / 0.5 = 0.2 %: `c`'s tie stands.
  add("wires", "none", 1.0, 1e-6);
  add("wires", "c", 0.95, 1e-6);
  const std::vector<Group> groups = GroupRows(rows);
  Document doc;
  ReferenceNoiseSection(doc, Pointers(groups));
  const std::string md = ToMarkdown(doc);
  EXPECT_NE(md.find("5 of 5 rows have `tv_err_floor` above 0.5"), std::string::npos) << md;
  EXPECT_NE(md.find("0 of the 3 comparisons with `none` are paired"), std::string::npos) << md;
  EXPECT_NE(md.find("(1 rows: fainter than any visible flicker"), std::string::npos) << md;
  EXPECT_NE(md.find("1 rows (20.0 %) are unresolved"), std::string::npos) << md;
  EXPECT_NE(md.find("not met in this store"), std::string::npos) << md;
  EXPECT_NE(md.find("sphere / ggx:0.01 / orbit: 1 rows"), std::string::npos) << md;
  EXPECT_EQ(md.find("wires / ggx:0.01 / orbit:"), std::string::npos) << md;
}

TEST(ReportOverview, UnconvergedShotIsLeftOutAndListed) {
  std::vector<JobResult> rows;
  for (const char* material : {"ggx:0.01", "ggx:0.5", "ggx:0.2"}) {
    rows.push_back(Row("sphere", material, "none", 1.0, 0.0));
    rows.push_back(Row("sphere", material, "tk21", std::string(material) == "ggx:0.5" ? 0.9 : 0.1, 0.0));
  }
  ShotCheck ok, bad;
  ok.converged = true, ok.spp = 8, ok.check_spp = 16;
  bad.converged = false, bad.spp = 8, bad.check_spp = 16, bad.d_tv_ref = 0.25, bad.d_energy_bias = 0.001;
  bad.d_tv_err = 0.3, bad.unconverged_pixels = 42;
  for (JobResult& r : rows) {
    if (r.job.material == "ggx:0.5") r.shot = bad;
    if (r.job.material == "ggx:0.01") r.shot = ok;
  }
  const std::vector<Group> groups = GroupRows(rows);
  std::vector<const Group*> included;
  for (const Group& g : groups)
    if (ConvergenceOf(g) != Convergence::kUnconverged) included.push_back(&g);
  EXPECT_EQ(included.size(), 2u);
  const auto summaries = Summarise(included);
  EXPECT_EQ(Find(summaries, "tk21").ratio.n, 2);
  EXPECT_NEAR(Find(summaries, "tk21").ratio.median, 0.1, 1e-12);  // 0.9 of the unconverged shot left out
  const std::string md = ToMarkdown(BuildDocument(groups, "t", rows.size()));
  const std::size_t left_out = md.find("### Shots left out");
  ASSERT_NE(left_out, std::string::npos);
  EXPECT_NE(md.find("- **unconverged** sphere / ggx:0.5 / orbit: spp 8 vs 16 per axis; changes: tv_ref 0.25 "
                    "(tolerance 0.1), energy_bias 0.001 (tolerance 0.02), tv_err 0.3 (tolerance 0.1); 42 pixel-frames",
                    left_out),
            std::string::npos)
      << md;
  EXPECT_NE(
      md.find("**unchecked** (no convergence check in the store; kept in the overview): sphere / ggx:0.2 / orbit"),
      std::string::npos)
      << md;
  EXPECT_NE(md.find("Reference: **unconverged**, left out of the answer"), std::string::npos);
}

TEST(ReportTables, OrderedBySceneThenAlpha) {
  std::vector<JobResult> rows;
  // Alphabetical order would put beckmann:0.3 first and ggx:0.1,0.02 (α 0.045) after ggx:0.05.
  for (const char* material : {"beckmann:0.3", "ggx:0.05", "ggx:0.1,0.02", "ggx:0.2"})
    for (const char* scene : {"wires", "bumpy-plane"}) rows.push_back(Row(scene, material, "none", 1.0, 0.0));
  const std::vector<Group> groups = GroupRows(rows);
  std::vector<std::string> keys;
  for (const Group& g : groups) keys.push_back(g.key);
  const std::vector<std::string> expected = {"bumpy-plane / ggx:0.1,0.02 / orbit / quad",
                                             "bumpy-plane / ggx:0.05 / orbit / quad",
                                             "bumpy-plane / ggx:0.2 / orbit / quad",
                                             "bumpy-plane / beckmann:0.3 / orbit / quad",
                                             "wires / ggx:0.1,0.02 / orbit / quad",
                                             "wires / ggx:0.05 / orbit / quad",
                                             "wires / ggx:0.2 / orbit / quad",
                                             "wires / beckmann:0.3 / orbit / quad"};
  EXPECT_EQ(keys, expected);
  const std::string md = ToMarkdown(BuildDocument(groups, "t", rows.size()));
  EXPECT_LT(md.find("### bumpy-plane / ggx:0.2 / orbit / quad"), md.find("### bumpy-plane / beckmann:0.3 / orbit"));
}

// Benchmarks from two devices: one cost column per device, never a ratio mixing them.
TEST(ReportTables, CostsFromTwoDevicesStaySeparate) {
  std::vector<JobResult> rows;
  for (auto [material, device, ratio] :
       {std::tuple<const char*, const char*, double>{"ggx:0.01", "gpu-a", 1.5}, {"ggx:0.02", "gpu-b", 3.0}}) {
    rows.push_back(Row("sphere", material, "none", 1.0, 0.0));
    Bench(rows.back(), 1.0, device);
    rows.push_back(Row("sphere", material, "tk21", 0.5, 0.0));
    Bench(rows.back(), ratio, device);
  }
  // And one table whose rows were benchmarked on different devices.
  rows.push_back(Row("wires", "ggx:0.01", "none", 1.0, 0.0));
  Bench(rows.back(), 1.0, "gpu-a");
  rows.push_back(Row("wires", "ggx:0.01", "tk21", 0.5, 0.0));
  Bench(rows.back(), 2.0, "gpu-b");
  rows.back().device = "other";
  const std::vector<Group> groups = GroupRows(rows);
  const auto summaries = Summarise(Pointers(groups));
  const VariantSummary& tk21 = Find(summaries, "tk21");
  ASSERT_EQ(tk21.cost_ratio.size(), 2u);
  EXPECT_NEAR(tk21.cost_ratio.at("gpu-a").median, 1.5, 1e-12);
  EXPECT_NEAR(tk21.cost_ratio.at("gpu-b").median, 2.5, 1e-12);  // 3.0 and 2.0, both measured on gpu-b
  const std::string md = ToMarkdown(BuildDocument(groups, "t", rows.size()));
  // The class leaderboard names each device's median; the mixed table says its rows' devices differ.
  EXPECT_NE(md.find("| 1.50× on gpu-a; 3.00× on gpu-b |"), std::string::npos) << md;  // small curved
  EXPECT_NE(md.find("| 2.00× |"), std::string::npos) << md;                         // thin: gpu-b only
  EXPECT_NE(md.find("Cost: each row's ratio to `none` on its own benchmark device"), std::string::npos) << md;
  const Costs one_device = CostsOf(groups.front());
  EXPECT_EQ(one_device.ms, (std::vector<double>{2.0, 3.0}));  // benchmark median ms, not the render's
}

TEST(Report, ParetoFrontKeepsOnlyUndominatedPoints) {
  // (cost, error): b dominates c; a is cheapest; d is most accurate; e ties a's cost but is worse.
  const std::vector<double> cost{1, 2, 3, 5, 1};
  const std::vector<double> error{10, 5, 6, 1, 11};
  EXPECT_EQ(ParetoFront(cost, error), (std::vector<int>{0, 1, 3}));
}
// An RFC 4180 reader written apart from the writer: quoted fields may hold
// commas, doubled quotes and line breaks; records end in CRLF or LF.
std::vector<std::vector<std::string>> ParseCsv(const std::string& text) {
  std::vector<std::vector<std::string>> records(1);
  std::string field;
  bool quoted = false, field_started = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"')
        field += '"', ++i;
      else if (c == '"')
        quoted = false;
      else
        field += c;
    } else if (c == '"' && !field_started) {
      quoted = field_started = true;
    } else if (c == ',') {
      records.back().push_back(field), field.clear(), field_started = false;
    } else if (c == '\r' || c == '\n') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      records.back().push_back(field), field.clear(), field_started = false;
      records.emplace_back();
    } else {
      field += c, field_started = true;
    }
  }
  if (field_started || !records.back().empty()) records.back().push_back(field);
  if (records.back().empty()) records.pop_back();
  return records;
}

TEST(Csv, FieldsWithCommasQuotesAndNewlinesReadBackAsWritten) {
  const std::vector<std::string> header = {"name", "params", "note"};
  const std::vector<std::vector<std::string>> rows = {{"tk19", "{\"kappa\":0.18,\"sigma2\":0.25}", "plain"},
                                                      {"a,b", "say \"hi\"", "two\nlines"},
                                                      {"", "trailing space ", "\"\""}};
  CsvTable table(header);
  for (const auto& r : rows) table.AddRow(r);
  const auto read = ParseCsv(table.Text());
  ASSERT_EQ(read.size(), 1 + rows.size()) << table.Text();
  EXPECT_EQ(read[0], header);
  for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(read[i + 1], rows[i]) << i;
  EXPECT_EQ(CsvNumber(std::nan("")), "");
  EXPECT_THROW(table.AddRow({"short"}), std::logic_error);
}

TEST(Report, WritesTablesCsvAndPlotScripts) {
  TempDir dir;
  std::vector<JobResult> rows;
  for (const char* v : {"none", "tk19", "supersample-2"}) {
    JobResult r = MakeResult(v, 1.0, 2.0);
    r.metrics["flicker"] = {{"flicker_index", 0.1}, {"freq_hz", {0.0, 7.5, 15.0}}, {"psd", {1e-3, 2e-3, 0.0}}};
    rows.push_back(r);
  }
  std::vector<std::string> warnings;
  rows[1].job.params = {{"kappa", 0.18}, {"sigma2", 0.25}};  // a JSON field with a comma and quotes
  rows[1].metrics["region"] = "highlight";
  for (JobResult& r : rows) r.device = "gpu, \"fast\"";  // one device: the Pareto plots compare its times
  ASSERT_TRUE(WriteReport(rows, "t", (dir.path() / "rep").string(), &warnings));
  std::ifstream csv_in(dir.path() / "rep" / "report.csv", std::ios::binary);
  const auto csv = ParseCsv(std::string((std::istreambuf_iterator<char>(csv_in)), {}));
  ASSERT_EQ(csv.size(), 4u);
  // The original columns first, in their order; intervals, convergence and benchmark after them.
  const std::vector<std::string> header = {
      "scene",    "material", "camera",      "variant",           "params", "derivatives",   "region",
      "tv_ratio", "tv_err",   "energy_bias", "temporal_diff_err", "relmse", "flicker_index", "ms_per_frame",
      "device",   "driver"};
  ASSERT_GE(csv[0].size(), header.size());
  EXPECT_EQ(std::vector<std::string>(csv[0].begin(), csv[0].begin() + header.size()), header);
  for (const char* added : {"tv_err_lo", "tv_err_hi", "flicker_index_hi", "tv_err_floor", "reference", "d_tv_ref",
                            "bench_median_ms", "bench_ratio_to_none", "bench_device"})
    EXPECT_NE(std::find(csv[0].begin(), csv[0].end(), added), csv[0].end()) << added;
  const std::vector<std::string>* tk19 = nullptr;
  for (const auto& record : csv) {
    EXPECT_EQ(record.size(), csv[0].size());
    if (record[3] == "tk19") tk19 = &record;
  }
  ASSERT_NE(tk19, nullptr);
  EXPECT_EQ(nlohmann::json::parse((*tk19)[4]), nlohmann::json(rows[1].job.params));
  EXPECT_EQ((*tk19)[6], "highlight");
  EXPECT_EQ((*tk19)[14], rows[1].device);
  std::ifstream md(dir.path() / "rep" / "report.md");
  std::string text((std::istreambuf_iterator<char>(md)), {});
  EXPECT_NE(text.find("## Overview"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir.path() / "rep" / "sphere___ggx_0_02___orbit___quad_pareto_tv_err.gp"));
  EXPECT_TRUE(fs::exists(dir.path() / "rep" / "sphere___ggx_0_02___orbit___quad_pareto_relmse.gp"));
  EXPECT_TRUE(fs::exists(dir.path() / "rep" / "sphere___ggx_0_02___orbit___quad_spectra.gp"));
  EXPECT_NE(text.find("| `tk19 kappa=0.18 sigma2=0.25` | "), std::string::npos) << text;
  // Scripts name their outputs by the final names: rerunning one rebuilds its plot.
  std::ifstream gp(dir.path() / "rep" / "sphere___ggx_0_02___orbit___quad_spectra.gp");
  std::string script((std::istreambuf_iterator<char>(gp)), {});
  EXPECT_NE(script.find("set output 'sphere___ggx_0_02___orbit___quad_spectra.svg'"), std::string::npos) << script;
  EXPECT_NE(script.find("noenhanced"), std::string::npos);
  for (const auto& e : fs::directory_iterator(dir.path() / "rep"))  // no staging left behind
    EXPECT_NE(e.path().filename().string().front(), '.') << e.path();
  EXPECT_FALSE(WriteReport({}, "t", (dir.path() / "empty").string(), &warnings));
  EXPECT_FALSE(fs::exists(dir.path() / "empty"));
}

// The Method section names the precision the costs were timed to (each
// row's own, the spec's benchmark.precision) and counts those that reached
// it: a ratio of 1.2 [1.15, 1.25] is within ±5 % but not within ±3 %.
TEST(Report, CostPrecisionIsTheOneTheCostsWereTimedTo) {
  auto method = [](double precision) {
    TempDir dir;
    std::vector<JobResult> rows;
    for (const char* v : {"none", "tk19", "supersample-2"}) {
      rows.push_back(MakeResult(v, 1.0, 2.0));
      Bench(rows.back(), v == std::string("none") ? 1.0 : 1.2);
      BenchmarkCost& c = *rows.back().cost;
      c.precision = precision;
      const double half = v == std::string("tk19") ? 0.05 : 0.3;  // supersample-2 stopped at the cap
      c.ratio_lo = c.ratio_to_none - half, c.ratio_hi = c.ratio_to_none + half;
    }
    std::vector<std::string> warnings;
    EXPECT_TRUE(WriteReport(rows, "t", (dir.path() / "rep").string(), &warnings));
    return ReadText(dir.path() / "rep" / "report.md");
  };
  const std::string at5 = method(0.05), at3 = method(0.03);
  EXPECT_NE(at5.find("each variant timed until its interval is within ±5 % or the spec's cap was reached (1 of 2 "
                     "costs here reached it)"),
            std::string::npos)
      << at5;
  EXPECT_NE(at3.find("within ±3 % or the spec's cap was reached (0 of 2 costs here reached it)"), std::string::npos)
      << at3;
}

// The spectra of a group of twenty variants: twenty different line styles,
// where gnuplot's own cycle repeats after eight.
TEST(Report, SpectraOfManyVariantsLookDifferent) {
  TempDir dir;
  std::vector<JobResult> rows;
  for (int i = 0; i < 20; ++i) {
    JobResult r = MakeResult("k16-beckmann-rect", 0.05 * (i + 1), 2.0);
    r.metrics["flicker"] = {{"flicker_index", 0.1}, {"freq_hz", {0.0, 7.5}}, {"psd", {1e-3, 2e-3}}};
    rows.push_back(r);
  }
  std::vector<std::string> warnings;
  ASSERT_TRUE(WriteReport(rows, "t", (dir.path() / "rep").string(), &warnings));
  std::ifstream gp(dir.path() / "rep" / "sphere___ggx_0_02___orbit___quad_spectra.gp");
  std::set<std::string> styles;
  for (std::string line; std::getline(gp, line);) {
    const auto lc = line.find("lc rgb");
    const auto title = line.find(" title ");
    if (lc != std::string::npos && title != std::string::npos) styles.insert(line.substr(lc, title - lc));
  }
  EXPECT_EQ(styles.size(), 20u);
}

// report.html holds what report.md holds, on one page that needs nothing
// else: every plot inlined, no script, no external reference.
TEST(Report, HtmlIsSelfContained) {
  TempDir dir;
  std::vector<JobResult> rows;
  for (const char* material : {"ggx:0.01", "ggx:0.5"})
    for (auto [v, err, bias] : {std::tuple<const char*, double, double>{"none", 1.0, 0.0},
                                {"tk21", 0.3, 0.02},
                                {"vlachos15", 0.1, -0.4},
                                {"supersample-2", 0.5, 0.0}}) {
      rows.push_back(Row("sphere", material, v, err, bias, 0.05));
      rows.back().metrics["flicker"] = {
          {"flicker_index", err}, {"freq_hz", {0.0, 7.5, 15.0}}, {"psd", {1e-3, 2e-3, 1e-4}}};
      Bench(rows.back(), 1.0 + err);
    }
  std::vector<std::string> warnings;
  ASSERT_TRUE(WriteReport(rows, "Self <contained>", (dir.path() / "rep").string(), &warnings));
  const std::string html = ReadText(dir.path() / "rep" / "report.html");
  const std::string md = ReadText(dir.path() / "rep" / "report.md");
  ASSERT_FALSE(html.empty());
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  for (const char* external : {"src=\"http", "href=\"http", "src='http", "href='http", "<script", "<link", "@import"})
    EXPECT_EQ(html.find(external), std::string::npos) << external;
  EXPECT_NE(html.find("<title>Self &lt;contained&gt;</title>"), std::string::npos);
  for (const char* section : {kAnswerHeading, kContentsHeading, kOverviewHeading, kCellsHeading, kLeaderboardHeading,
                              kHeatmapHeading, kReferenceNoiseHeading,
                              kExcludedHeading, kShotsHeading, kMethodHeading}) {
    EXPECT_NE(html.find(">" + std::string(section) + "</h"), std::string::npos) << section;
    EXPECT_NE(md.find("# " + std::string(section) + "\n"), std::string::npos) << section;
  }
  EXPECT_NE(html.find("<details><summary>every column</summary>"), std::string::npos);
  EXPECT_NE(html.find("<th>tv_err_floor</th>"), std::string::npos);
  EXPECT_EQ(md.find("| tv_err_floor |"), std::string::npos);  // report.md keeps its 7 columns
  EXPECT_NE(html.find("<code>tk21</code>"), std::string::npos);
  if (fs::exists(dir.path() / "rep" / "heatmap.svg")) {  // gnuplot installed: the plots are inlined, not linked
    EXPECT_NE(html.find("<svg"), std::string::npos);
    EXPECT_EQ(html.find("<?xml"), std::string::npos);
    EXPECT_EQ(html.find("<img"), std::string::npos);
    EXPECT_EQ(html.find("was not drawn"), std::string::npos);
  } else {
    GTEST_LOG_(INFO) << "gnuplot missing: plots not checked";
  }
  // The heatmap crosses the filter that loses 40 % energy, in both shots.
  const std::string crosses = ReadText(dir.path() / "rep" / "heatmap_crosses.dat");
  EXPECT_EQ(std::count(crosses.begin(), crosses.end(), '\n'), 3);
}

}  // namespace
}  // namespace shimmer::experiments
