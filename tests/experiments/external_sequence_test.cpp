// External sequences in specs (section "sequences"): parsing and its errors,
// job ids that hash the frames' content but not where they lie, measuring
// without a device, and their place in the report's groups and costs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "report_parts.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/experiments/spec.h"
#include "shimmer/metrics/metrics_report.h"
#include "test_sequences.h"

namespace shimmer::experiments {
namespace {

namespace fs = std::filesystem;
using metrics::testing::Layout;
using metrics::testing::SequenceSpec;
using metrics::testing::WriteSequence;

// A flickering highlight in the test, a steady one in the reference.
void WriteFrames(const fs::path& dir, int frames, int size, float flicker) {
  SequenceSpec s;
  s.frames = frames, s.width = size, s.height = size;
  s.layout = Layout::kSpecularLayer;
  s.value = [=](int t, int x, int y) {
    const float spot = (x - size / 2) * (x - size / 2) + (y - size / 2) * (y - size / 2) < 9 ? 2.0f : 0.05f;
    return spot * (1.0f + flicker * float((t + x) % 2));
  };
  WriteSequence(dir, s);
}

struct Folder {
  shimmer::testing::TempDir temp;
  fs::path dir = temp.path();
  Folder() {
    WriteFrames(dir / "frames" / "test", 8, 16, 0.5f);
    WriteFrames(dir / "frames" / "ref", 8, 16, 0.0f);
    fs::create_directories(dir / "specs");
  }
  Result<Spec> Parse(const std::string& sequences, const std::string& rendered = "") const {
    const std::string text = R"({"name": "e", )" + rendered + R"("sequences": )" + sequences + "}";
    return ParseSpec(text, (dir / "specs" / "e.json").string());
  }
};

constexpr const char* kOne = R"([{"label": "engine", "test": "../frames/test", "reference": "../frames/ref"}])";

TEST(ExternalSequenceSpec, ASpecOfSequencesAloneExpandsToExternalJobs) {
  Folder f;
  auto spec = f.Parse(kOne);
  ASSERT_TRUE(spec.ok()) << spec.error();
  ASSERT_EQ(spec->sequences.size(), 1u);
  const std::vector<Job> jobs = ExpandJobs(*spec);
  ASSERT_EQ(jobs.size(), 1u);
  const Job& job = jobs[0];
  ASSERT_TRUE(job.external);
  EXPECT_EQ(job.variant, "engine");
  EXPECT_EQ(job.scene, "external");
  EXPECT_EQ(job.derivatives, kExternalDerivatives);
  EXPECT_EQ(job.width, 16);
  EXPECT_EQ(job.frames, 8);
  EXPECT_EQ(job.external->test, (f.dir / "frames" / "test").string());
  EXPECT_EQ(job.external->test_hash.size(), 16u);
  EXPECT_NE(job.external->test_hash, job.external->reference_hash);
  // The stored job reads back as it was written.
  EXPECT_EQ(Job::FromJson(job.ToJson()).ToJson(), job.ToJson());
  EXPECT_EQ(*Job::FromJson(job.ToJson()).external, *job.external);
}

TEST(ExternalSequenceSpec, IdsHashTheFramesNotWhereTheyLie) {
  Folder f;
  const Job first = ExpandJobs(*f.Parse(kOne))[0];
  fs::copy(f.dir / "frames", f.dir / "moved", fs::copy_options::recursive);
  const Job moved = ExpandJobs(*f.Parse(R"([{"label": "engine", "test": "../moved/test",
                                             "reference": "../moved/ref"}])"))[0];
  EXPECT_EQ(JobId(moved), JobId(first));
  EXPECT_EQ(ReferenceId(moved), ReferenceId(first));
  // Edited frames of the test are a new job with the same reference.
  WriteFrames(f.dir / "moved" / "test", 8, 16, 0.25f);
  const Job edited = ExpandJobs(*f.Parse(R"([{"label": "engine", "test": "../moved/test",
                                              "reference": "../moved/ref"}])"))[0];
  EXPECT_NE(JobId(edited), JobId(first));
  EXPECT_EQ(ReferenceId(edited), ReferenceId(first));
  // No kernel renders their pixels: a kernel moves no id; the metrics code does.
  JobSources a, b;
  a.metrics = b.metrics = "m";
  a.test.kernel = "a", b.test.kernel = "b";
  EXPECT_EQ(JobIdFrom(first, a), JobIdFrom(first, b));
  b.metrics = "m2";
  EXPECT_NE(JobIdFrom(first, a), JobIdFrom(first, b));
}

TEST(ExternalSequenceSpec, EveryBadEntryIsOneErrorNamingTheEntryAndKey) {
  Folder f;
  WriteFrames(f.dir / "frames" / "small", 8, 8, 0.0f);
  WriteFrames(f.dir / "frames" / "short", 4, 16, 0.0f);
  const std::string ok = R"("test": "../frames/test", "reference": "../frames/ref")";
  const std::string rendered =
      R"("scenes": ["sphere"], "materials": ["ggx:0.1"], "cameras": ["orbit"], "variants": ["none"], )";
  struct Case {
    std::string sequences, rendered, expected;
  };
  const Case cases[] = {
      {R"([{"test": "../frames/test", "reference": "../frames/ref"}])", "", "sequences[0]: needs \"label\""},
      {R"([{"label": "a b", )" + ok + "}]", "", "sequences[0].label: must be 1 to 64 letters"},
      {R"([{"label": "a", "test": "../nope", "reference": "../frames/ref"}])", "", "sequences[0].test:"},
      {R"([{"label": "a", "test": "../frames/test", "reference": "../frames/small"}])", "",
       "they must be the same size"},
      {R"([{"label": "a", "test": "../frames/test", "reference": "../frames/short"}])", "",
       "they must be as long"},
      {R"([{"label": "a", "test": 3, "reference": "../frames/ref"}])", "", "sequences[0].test: must be the path"},
      {R"([{"label": "a", )" + ok + R"(, "cost": {"ms_per_frame": 1}}])", "", "sequences[0].cost: must be"},
      {R"([{"label": "a", )" + ok + R"(, "cost": {"ms_per_frame": -1, "device": "x"}}])", "",
       "sequences[0].ms_per_frame: must be > 0"},
      {R"([{"label": "a", )" + ok + R"(, "colour": 1}])", "", "sequences[0].colour: unknown key"},
      {R"([{"label": "a", )" + ok + R"(, "shot": {"scene": ""}}])", "", "sequences[0].scene: must be a string"},
      {R"([{"label": "a", )" + ok + R"(, "fps": 0}])", "", "sequences[0].fps: must be > 0"},
      {R"([{"label": "a", )" + ok + "}, {\"label\": \"a\", " + ok + "}]", "",
       "sequences[1].label: 'a' names two sequences"},
      {R"([{"label": "none", )" + ok + R"(, "shot": {"scene": "sphere", "material": "ggx:0.1", "camera": "orbit"}}])",
       rendered, "the spec renders `none` of the shot sphere / ggx:0.1 / orbit already"},
      {R"([])", "", "sequences: must be a non-empty list"},
      {kOne, R"("scenes": ["sphere"], )", "materials: is required with the other keys"},
  };
  for (const Case& c : cases) {
    auto spec = f.Parse(c.sequences, c.rendered);
    ASSERT_FALSE(spec.ok()) << c.sequences;
    EXPECT_NE(spec.error().find(c.expected), std::string::npos) << c.sequences << "\n" << spec.error();
    EXPECT_NE(spec.error().find("e.json:"), std::string::npos) << spec.error();
  }
}

TEST(ExternalSequenceRun, MeasuresWithoutADeviceAsTheMetricsLibraryDoes) {
  Folder f;
  auto spec = f.Parse(kOne);
  ASSERT_TRUE(spec.ok()) << spec.error();
  RunOptions options;
  options.db_path = (f.dir / "e.db").string();
  options.work_dir = (f.dir / "work").string();
  const RunSummary summary = RunJobs(ExpandJobs(*spec), options);
  ASSERT_FALSE(summary.error) << summary.error->message;
  EXPECT_EQ(summary.computed, 1);
  auto store = ResultStore::Open(options.db_path, ResultStore::Mode::kReadOnly);
  ASSERT_TRUE(store) << store.error();
  const std::vector<JobResult> rows = *(*store)->All();
  ASSERT_EQ(rows.size(), 1u);
  metrics::MetricsOptions mo;
  mo.test = f.dir / "frames" / "test";
  mo.reference = f.dir / "frames" / "ref";
  mo.highlight_mask = true;
  mo.highlight.threshold = spec->metrics.highlight_threshold;
  mo.request.fps = spec->fps;  // the frames have no sequence.json: the spec's fps, as `--fps` would give
  const nlohmann::json direct = metrics::ToJson(*metrics::ComputeMetrics(mo));
  for (const char* key : {"tv_err", "tv_ratio", "energy_bias", "relmse", "pixels"})
    EXPECT_EQ(rows[0].metrics[key], direct[key]) << key;
  EXPECT_EQ(rows[0].metrics["ci95"], direct["ci95"]);
  EXPECT_GT(rows[0].metrics["tv_err"].get<double>(), 0);
  // Frames changed after the spec was read are refused, not stored under the old id.
  WriteFrames(f.dir / "frames" / "test", 8, 16, 0.1f);
  const RunSummary changed = RunJobs(ExpandJobs(*spec), options);
  ASSERT_TRUE(changed.error);
  EXPECT_NE(changed.error->message.find("the frames changed since the spec was read"), std::string::npos)
      << changed.error->message;
}

JobResult Row(const std::string& variant, const std::string& derivatives, double tv_err, bool external,
              double ms = 0) {
  JobResult r;
  r.job.scene = "sphere", r.job.material = "ggx:0.1", r.job.camera = "orbit";
  r.job.variant = variant, r.job.derivatives = derivatives;
  if (external) {
    ExternalFrames e;
    e.ms_per_frame = ms, e.device = "gpu";
    r.job.external = e;
  }
  r.id = variant + derivatives + (external ? "x" : "");
  r.metrics = {{"tv_err", tv_err}, {"energy_bias", 0.0}};
  return r;
}

TEST(ExternalSequenceReport, ARowOfARenderedShotJoinsEveryDerivativeTableMarkedExternal) {
  const std::vector<JobResult> rows = {Row("none", "quad", 1.0, false), Row("tk19", "quad", 0.5, false),
                                       Row("tk19", "analytic", 0.4, false),
                                       Row("engine", kExternalDerivatives, 0.25, true)};
  const std::vector<report::Group> groups = report::GroupRows(rows);
  ASSERT_EQ(groups.size(), 2u);  // analytic and quad; no table of "external"
  for (const report::Group& g : groups) {
    ASSERT_EQ(g.rows.size(), 3u) << g.key;
    bool found = false;
    for (const report::Sample& s : report::SamplesOf(g))
      if (s.row->job.external) {
        found = true;
        EXPECT_EQ(report::Label(*s.row), "engine (external)");
        EXPECT_DOUBLE_EQ(s.ratio, 0.25);  // against the rendered none
      }
    EXPECT_TRUE(found) << g.key;
  }
}

TEST(ExternalSequenceReport, AnEngineShotBringsItsOwnNoneAndCosts) {
  std::vector<JobResult> rows = {Row("none", kExternalDerivatives, 2.0, true, 0.8),
                                 Row("taa", kExternalDerivatives, 1.0, true, 1.2),
                                 Row("clamp", kExternalDerivatives, 1.5, true)};
  JoinExternalCosts(rows);
  ASSERT_TRUE(rows[1].cost);
  EXPECT_DOUBLE_EQ(rows[1].cost->ratio_to_none, 1.5);
  EXPECT_EQ(rows[1].cost->device, "gpu");
  EXPECT_FALSE(rows[2].cost);  // no cost given
  const std::vector<report::Group> groups = report::GroupRows(rows);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].derivatives, kExternalDerivatives);
  ASSERT_NE(report::NoneOf(groups[0]), nullptr);
  EXPECT_EQ(report::NoneOf(groups[0])->job.variant, "none");
  const std::vector<report::VariantSummary> summaries = report::Summarise({&groups[0]});
  ASSERT_FALSE(summaries.empty());
  EXPECT_EQ(summaries.front().label, "taa (external)");  // lowest ratio first
  EXPECT_DOUBLE_EQ(summaries.front().ratio.median, 0.5);
  EXPECT_DOUBLE_EQ(summaries.front().cost_ratio.at("gpu").median, 1.5);
}

}  // namespace
}  // namespace shimmer::experiments
