// Job ids re-run exactly what a change changes (docs/guide.md, Job
// ids): shader edits through the renderer's source overrides, scene files
// and normal maps edited on disk, a store from before per-kernel ids. No
// device: ids come from the kernel's SPIR-V and the bytes it would read.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "shimmer/experiments/job.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/experiments/spec.h"
#include "shimmer/metrics/metrics_version.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"
#include "test_hooks.h"

namespace shimmer::experiments {
namespace {

namespace fs = std::filesystem;

// A scene file with a normal-mapped plane and a sphere, and its map.
struct SceneFiles {
  fs::path dir = fs::temp_directory_path() / ("shimmer-job-id-" + std::to_string(::getpid()));
  SceneFiles() {
    fs::create_directories(dir);
    WriteMap(0.2);
    WriteScene(1.0);
  }
  ~SceneFiles() { fs::remove_all(dir); }
  std::string scene() const { return (dir / "s.json").string(); }
  void WriteScene(double radius) const {
    std::ofstream(dir / "s.json")
        << R"({"name": "mine", "primitives": [{"type": "sphere", "center": [0, 0, 0], "radius": )" << radius
        << R"(}, {"type": "plane", "height": -1, "normal_map": {"file": "m.png"}}]})";
  }
  // A 16 x 16 map of slope `s` along x; bumped in time so that the process's
  // map cache sees a rewrite.
  void WriteMap(double s) const {
    cv::Mat image(16, 16, CV_8UC3);
    const double len = std::sqrt(1 + s * s);
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        const double nx = (x % 2 ? s : -s) / len, nz = 1 / len;
        auto byte = [](double v) { return uchar(std::lround((v + 1) * 127.5)); };
        image.at<cv::Vec3b>(y, x) = cv::Vec3b(byte(nz), byte(0), byte(nx));  // BGR
      }
    const fs::path file = dir / "m.png";
    ASSERT_TRUE(cv::imwrite(file.string(), image));
    static int bump = 0;
    fs::last_write_time(file, fs::file_time_type::clock::now() + std::chrono::seconds(++bump));
  }
};

Spec TinySpec(const std::string& scene_file) {
  const std::string text = R"({
    "name": "tiny",
    "scenes": ["sphere", ")" + scene_file + R"("],
    "materials": ["ggx:0.05"],
    "cameras": ["orbit"],
    "variants": ["none", "tk19", "tk21", "k16-ggx-rect-stable"],
    "derivatives": ["quad"],
    "size": [16, 16],
    "frames": 2,
    "reference": {"spp": 2}
  })";
  auto spec = ParseSpec(text, "tiny.json");
  EXPECT_TRUE(spec) << spec.error();
  return *spec;
}

struct Ids {
  std::map<std::string, std::string> job, frames, reference;  // by "scene variant"
};
Ids IdsOf(const std::vector<Job>& jobs) {
  ForgetSources();
  Ids ids;
  for (const Job& j : jobs) {
    const std::string name = j.scene + " " + j.variant;
    auto sources = SourcesOf(j);
    EXPECT_TRUE(sources) << name << ": " << sources.error();
    if (!sources) continue;
    ids.job[name] = JobIdFrom(j, *sources);
    ids.frames[name] = FramesIdFrom(j, *sources);
    ids.reference[name] = ReferenceIdFrom(j, *sources);
  }
  return ids;
}
// The names whose id moved.
std::set<std::string> Moved(const std::map<std::string, std::string>& a,
                            const std::map<std::string, std::string>& b) {
  std::set<std::string> moved;
  for (const auto& [name, id] : a)
    if (b.at(name) != id) moved.insert(name);
  return moved;
}

// The text of an embedded kernel or shading-core file.
std::string SourceText(std::string_view name) {
  for (const auto& [file, text] : shading::GlslSources())
    if (file == name) return std::string(text);
  const fs::path kernel = fs::path(SHIMMER_SOURCE_DIR) / "renderer" / "shaders" / std::string(name);
  std::ifstream in(kernel);
  EXPECT_TRUE(in) << name;
  return std::string(std::istreambuf_iterator<char>(in), {});
}
std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

class JobIds : public ::testing::Test {
 protected:
  // Ids with `file` replaced by `text` while they are computed.
  Ids With(const std::string& file, const std::string& text) {
    render::testing::TestHooks hooks;
    hooks.source_overrides = {{file, text}};
    render::testing::ScopedTestHooks scoped(hooks);
    return IdsOf(jobs_);
  }
  void SetUp() override {
    jobs_ = ExpandJobs(TinySpec(files_.scene()));
    ASSERT_EQ(jobs_.size(), 8u);
    base_ = IdsOf(jobs_);
  }
  SceneFiles files_;
  std::vector<Job> jobs_;
  Ids base_;
};

TEST_F(JobIds, CommentsAndDeadCodeInAShaderMoveNothing) {
  // A comment in the shared core shifts every later line; dead code adds a
  // function no kernel calls.
  const Ids comment = With("ggx_rect.glsl", "// a comment\n// and another one\n" + SourceText("ggx_rect.glsl"));
  EXPECT_TRUE(Moved(base_.job, comment.job).empty());
  EXPECT_TRUE(Moved(base_.reference, comment.reference).empty());
  const Ids dead = With("variants.glsl", SourceText("variants.glsl") + "\nreal unusedHelper(real x) { return 3.0 * x; }\n");
  EXPECT_TRUE(Moved(base_.job, dead.job).empty());
  const Ids renamed = With("render.comp", Replaced(SourceText("render.comp"), "uint h2 = pcgHash(h);\n  return vec2(float(h >> 8), float(h2 >> 8))",
                                                   "uint second = pcgHash(h);\n  return vec2(float(h >> 8), float(second >> 8))"));
  EXPECT_TRUE(Moved(base_.job, renamed.job).empty());
}

TEST_F(JobIds, AHelperThatReadsAStructsFieldsMovesNothing) {
  // Inlined, the helper's struct argument becomes a local copy read through
  // field pointers; the canonical form splits it into plain values. Without
  // the scalar replacement pass this edit moved every filter kernel's hash.
  std::string text = Replaced(SourceText("render.comp"), "// The filter variants: one sample at the pixel centre,",
                              "vec3 beautyOf(PixelShade sh) { return sh.specular + sh.diffuse; }\n\n"
                              "// The filter variants: one sample at the pixel centre,");
  text = Replaced(text, "put3(CH_BEAUTY, idx, sh.specular + sh.diffuse);\n  put3(CH_SPECULAR, idx, sh.specular);\n"
                  "  put3(CH_DIFFUSE, idx, sh.diffuse);\n  put(CH_STDERR, idx, 0.0);",
                  "put3(CH_BEAUTY, idx, beautyOf(sh));\n  put3(CH_SPECULAR, idx, sh.specular);\n"
                  "  put3(CH_DIFFUSE, idx, sh.diffuse);\n  put(CH_STDERR, idx, 0.0);");
  const Ids moved = With("render.comp", text);
  EXPECT_TRUE(Moved(base_.job, moved.job).empty());
  EXPECT_TRUE(Moved(base_.reference, moved.reference).empty());
}

TEST_F(JobIds, AnEditOfOneVariantMovesThatVariantsJobsOnly) {
  const Ids edited = With("variants.glsl", Replaced(SourceText("variants.glsl"), "real k = min(sigma2 * spread, kappa);",
                                                    "real k = min(sigma2 * spread, 0.5 * kappa);"));
  const auto moved = Moved(base_.job, edited.job);
  EXPECT_EQ(moved, (std::set<std::string>{"sphere tk21", files_.scene() + " tk21"}));
  EXPECT_TRUE(Moved(base_.reference, edited.reference).empty());
}

TEST_F(JobIds, AnEditOfSharedCodeMovesTheJobsWhoseKernelsRunIt) {
  // normalSpread feeds tk19 and tk21, not `none` nor the GGX rectangle.
  const Ids edited = With("variants.glsl", Replaced(SourceText("variants.glsl"),
                                                    "min(dot(dx, dx) + dot(dy, dy), SPREAD_MAX)",
                                                    "min(dot(dx, dx) + 2.0 * dot(dy, dy), SPREAD_MAX)"));
  const std::string mine = files_.scene();
  EXPECT_EQ(Moved(base_.job, edited.job),
            (std::set<std::string>{"sphere tk19", "sphere tk21", mine + " tk19", mine + " tk21"}));
  EXPECT_TRUE(Moved(base_.reference, edited.reference).empty());
}

TEST_F(JobIds, AnEditOfTheReferenceLoopMovesReferencesAndRowsButNotFrames) {
  const Ids edited = With("render.comp", Replaced(SourceText("render.comp"), "(1.0 / 16777216.0)", "(1.0 / 16777217.0)"));
  EXPECT_EQ(Moved(base_.reference, edited.reference).size(), base_.reference.size());
  EXPECT_EQ(Moved(base_.job, edited.job).size(), base_.job.size());
  EXPECT_TRUE(Moved(base_.frames, edited.frames).empty());  // one sample per pixel: no jitter
}

TEST_F(JobIds, SceneFileAndNormalMapContentMoveTheirJobs) {
  const std::string mine = files_.scene();
  const std::set<std::string> of_mine{mine + " none", mine + " tk19", mine + " tk21", mine + " k16-ggx-rect-stable"};
  files_.WriteScene(0.5);
  const Ids scene = IdsOf(jobs_);
  EXPECT_EQ(Moved(base_.job, scene.job), of_mine);
  EXPECT_EQ(Moved(base_.reference, scene.reference), of_mine);
  files_.WriteScene(1.0);
  EXPECT_TRUE(Moved(base_.job, IdsOf(jobs_).job).empty());  // the same content again: the same ids
  files_.WriteMap(0.4);
  EXPECT_EQ(Moved(base_.job, IdsOf(jobs_).job), of_mine);
}

TEST_F(JobIds, ABuiltInSceneIsHashedByItsData) {
  // Built-in scenes are C++ data: what moves an id is the packed scene and
  // the cameras it gives, which this edit of the loaded scene stands for.
  const Job& job = jobs_.front();
  ASSERT_EQ(job.scene, "sphere");
  auto settings = RenderSettingsOf(job);
  ASSERT_TRUE(settings) << settings.error();
  const auto before = render::FingerprintRender(*settings);
  ASSERT_TRUE(before) << before.error();
  for (auto edit : {+[](render::RenderSettings& s) { s.scene.primitives[0].radius *= 1.01; },
                    +[](render::RenderSettings& s) { s.scene.rig.distance += 0.1; },
                    +[](render::RenderSettings& s) { s.scene.light.vec.x += 0.01; }}) {
    render::RenderSettings edited = *settings;
    edit(edited);
    const auto after = render::FingerprintRender(edited);
    ASSERT_TRUE(after) << after.error();
    EXPECT_EQ(after->kernel, before->kernel);
    EXPECT_NE(after->inputs, before->inputs);
  }
}

TEST_F(JobIds, ReferencesAreSharedAcrossDerivativeSources) {
  // The reference kernel shades N x N samples and never reads derivatives.
  Job quad = jobs_.front(), analytic = quad;
  analytic.derivatives = "analytic";
  EXPECT_EQ(ReferenceId(quad), ReferenceId(analytic));
}

TEST_F(JobIds, DryRunSaysWhyAndAStoreFromBeforeRerunsOnce) {
  const fs::path db = files_.dir / "r.db";
  {
    auto store = ResultStore::Open(db.string());
    ASSERT_TRUE(store) << store.error();
    // Row 0 done as now; row 1 made by another tk19 kernel; row 2 from
    // before per-kernel ids (no sources); the rest never ran.
    for (int k = 0; k < 3; ++k) {
      JobResult r;
      r.job = jobs_[k];
      JobSources sources = SourcesOf(r.job).value();
      if (k == 1) sources.test.kernel = "an-older-kernel";
      r.id = k == 2 ? "legacy-id" : JobIdFrom(r.job, sources);
      r.reference_id = ReferenceIdFrom(r.job, sources);
      if (k != 2) r.sources = sources.ToJson();
      r.metrics = {{"tv_err", 1}};
      ASSERT_TRUE((*store)->Insert(r));
    }
  }
  ASSERT_EQ(jobs_[1].variant, "tk19");
  RunOptions options;
  options.db_path = db.string();
  const auto plan = PlanRun(jobs_, options);
  ASSERT_TRUE(plan) << plan.error();
  EXPECT_EQ(plan->done, 1);
  EXPECT_EQ(plan->legacy_rows, 1u);
  ASSERT_EQ(plan->to_run.size(), jobs_.size() - 1);
  EXPECT_EQ(plan->to_run[0].why, (std::vector<std::string>{"kernel of `tk19` changed"}));
  EXPECT_EQ(plan->to_run[1].why, (std::vector<std::string>{kLegacyRowReason}));
  EXPECT_EQ(plan->to_run[2].why, (std::vector<std::string>{"new job"}));
  // Nothing was written by planning, and a missing store plans every job as new.
  auto store = ResultStore::Open(db.string(), ResultStore::Mode::kReadOnly);
  EXPECT_EQ((*store)->All()->size(), 3u);
  options.db_path = (files_.dir / "none.db").string();
  const auto fresh = PlanRun(jobs_, options);
  ASSERT_TRUE(fresh) << fresh.error();
  EXPECT_EQ(fresh->to_run.size(), jobs_.size());
  EXPECT_FALSE(fs::exists(options.db_path));
}

// An external sequence's row is current while its id is today's: measured by
// an older metrics code it is stale (the report leaves it out, prune drops
// it) like a rendered row, instead of showing beside its re-measured twin.
TEST(MetricsVersions, AnExternalRowOfAnOlderMetricsCodeIsNotCurrent) {
  Job job;
  job.variant = "engine";
  job.derivatives = kExternalDerivatives;
  job.external = ExternalFrames{"t", "r", "th", "rh", 0, ""};
  JobResult now, before;
  now.job = before.job = job;
  now.id = JobId(job);
  JobSources older;
  older.metrics = "an older metrics code";
  before.id = JobIdFrom(job, older);
  ASSERT_NE(now.id, before.id);
  const CurrentRowSet current = FindCurrentRows({now, before});
  EXPECT_EQ(current.jobs, (std::set<std::string>{now.id}));
  EXPECT_TRUE(current.costs.empty());  // no kernel of it is timed
}

TEST(MetricsVersions, OnlyRowsWithSparkleStatisticsCarryTheSparkleCodesVersion) {
  Job job;
  job.metrics.sparkle_threshold = 0;
  EXPECT_EQ(MetricsVersionOf(job), std::string(metrics::MetricsCodeVersion()));
  job.metrics.sparkle_threshold = 3;
  EXPECT_EQ(MetricsVersionOf(job),
            std::string(metrics::MetricsCodeVersion()) + "+sparkles:" + std::string(metrics::SparkleCodeVersion()));
  EXPECT_NE(metrics::MetricsCodeVersion(), metrics::SparkleCodeVersion());
}

TEST(MetricsVersions, ARowOfTheVersionBeforeTheSplitWasMeasuredByTodaysCodeOnlyWhileThatCodeIsUnchanged) {
  const MetricsVersionSplit split{"whole", "core", "sparkles"};
  Job plain, glints;
  glints.metrics.sparkle_threshold = 3;
  // Today's own versions.
  EXPECT_TRUE(MeasuredByTodaysMetrics("core", plain, "core", "sparkles", split));
  EXPECT_TRUE(MeasuredByTodaysMetrics("core+sparkles:s2", glints, "core", "s2", split));
  EXPECT_FALSE(MeasuredByTodaysMetrics("core", glints, "core", "sparkles", split));
  // A row of the whole version: today's code is the split's.
  EXPECT_TRUE(MeasuredByTodaysMetrics("whole", plain, "core", "sparkles", split));
  EXPECT_TRUE(MeasuredByTodaysMetrics("whole", glints, "core", "sparkles", split));
  // The sparkle code edited since: the rows with sparkles only are measured again.
  EXPECT_TRUE(MeasuredByTodaysMetrics("whole", plain, "core", "s2", split));
  EXPECT_FALSE(MeasuredByTodaysMetrics("whole", glints, "core", "s2", split));
  // The rest of the metrics code edited since: every row.
  EXPECT_FALSE(MeasuredByTodaysMetrics("whole", plain, "core2", "sparkles", split));
  EXPECT_FALSE(MeasuredByTodaysMetrics("whole", glints, "core2", "sparkles", split));
  // Any other version.
  EXPECT_FALSE(MeasuredByTodaysMetrics("older", plain, "core", "sparkles", split));
}

TEST_F(JobIds, RowsMeasuredByTodaysMetricsCodeUnderTheVersionBeforeTheSplitAreReKeyedNotRerun) {
  const fs::path db = files_.dir / "split.db";
  std::vector<Job> jobs(jobs_.begin(), jobs_.begin() + 2);
  {
    auto store = ResultStore::Open(db.string());
    ASSERT_TRUE(store) << store.error();
    for (const Job& job : jobs) {
      JobResult r;
      r.job = job;
      JobSources sources = SourcesOf(job).value();
      sources.metrics = std::string(kMetricsVersionSplit.before);
      r.id = JobIdFrom(job, sources);
      r.reference_id = ReferenceIdFrom(job, sources);
      r.sources = sources.ToJson();
      r.metrics = {{"tv_err", 1.5}};
      ASSERT_TRUE((*store)->Insert(r));
    }
  }
  RunOptions options;
  options.db_path = db.string();
  options.work_dir = (files_.dir / "frames").string();
  options.check_shots = false;
  const auto plan = PlanRun(jobs, options);
  ASSERT_TRUE(plan) << plan.error();
  const bool unchanged = metrics::MetricsCodeVersion() == kMetricsVersionSplit.core;
  if (!unchanged) {
    // The metrics code moved on since the split: the rows are measured once more.
    ASSERT_EQ(plan->to_run.size(), 2u);
    EXPECT_EQ(plan->to_run[0].why, (std::vector<std::string>{"metrics version changed"}));
    return;
  }
  EXPECT_TRUE(plan->to_run.empty());
  ASSERT_EQ(plan->to_rekey.size(), 2u);
  EXPECT_EQ(plan->to_rekey[0].why, (std::vector<std::string>{kRekeyReason}));
  // The run copies each row under today's id, measuring nothing.
  const RunSummary summary = RunJobs(jobs, options);
  ASSERT_FALSE(summary.error) << summary.error->message;
  EXPECT_EQ(summary.rekeyed, 2);
  EXPECT_EQ(summary.computed, 0);
  auto store = ResultStore::Open(db.string(), ResultStore::Mode::kReadOnly);
  ASSERT_TRUE(store) << store.error();
  for (const Job& job : jobs) {
    auto row = (*store)->Get(JobId(job));
    ASSERT_TRUE(row && *row);
    EXPECT_EQ((**row).metrics.at("tv_err"), 1.5);
    EXPECT_EQ(JobSources::FromJson((**row).sources).metrics, MetricsVersionOf(job));
  }
  const auto again = PlanRun(jobs, options);
  ASSERT_TRUE(again) << again.error();
  EXPECT_EQ(again->done, 2);
  EXPECT_TRUE(again->to_rekey.empty());
}

}  // namespace
}  // namespace shimmer::experiments
