#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "job.h"
#include "result_store.h"
#include "spec.h"

namespace shimmer::experiments {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("shimmer-store-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  TempDir() { fs::remove_all(path), fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

JobResult MakeResult(const std::string& variant, double fp_max, double tv_ratio) {
  JobResult r;
  r.job.scene = "sphere";
  r.job.material = "ggx:0.02";
  r.job.camera = "orbit";
  r.job.variant = variant;
  r.job.params = {{"fp_max", fp_max}};
  r.job.derivatives = "quad";
  r.job.width = r.job.height = 32;
  r.job.frames = 8;
  r.job.fps = 30;
  r.job.reference = {4, 0};
  r.id = JobId(r.job);
  r.reference_id = ReferenceId(r.job);
  r.metrics = {{"tv_ratio", tv_ratio}, {"tv_err", 0.5}, {"flicker", {{"flicker_index", 0.25}}}};
  r.gpu_ms_per_frame = 1.5;
  r.revision = "abc";
  r.core_version = ShadingCoreVersion();
  return r;
}

TEST(ResultStore, InsertThenFindAndReadBack) {
  TempDir dir;
  auto [store, error] = ResultStore::Open((dir.path / "r.db").string());
  ASSERT_TRUE(store) << error;
  const JobResult r = MakeResult("k16-beckmann-rect", 0.5, 3.0);
  EXPECT_FALSE(store->Has(r.id));
  ASSERT_EQ(store->Insert(r), "");
  EXPECT_TRUE(store->Has(r.id));
  const auto rows = store->All();
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].job.ToJson(), r.job.ToJson());
  EXPECT_EQ(rows[0].metrics, r.metrics);
  EXPECT_DOUBLE_EQ(rows[0].gpu_ms_per_frame, 1.5);
  // Reopening sees the same row: it was committed.
  store.reset();
  auto [again, error2] = ResultStore::Open((dir.path / "r.db").string());
  ASSERT_TRUE(again) << error2;
  EXPECT_TRUE(again->Has(r.id));
}

TEST(ResultStore, MergedShardsEqualOneStore) {
  TempDir dir;
  auto [a, ea] = ResultStore::Open((dir.path / "a.db").string());
  auto [b, eb] = ResultStore::Open((dir.path / "b.db").string());
  auto [all, ec] = ResultStore::Open((dir.path / "all.db").string());
  ASSERT_TRUE(a && b && all);
  std::vector<JobResult> results;
  for (int i = 0; i < 6; ++i) results.push_back(MakeResult("k16-beckmann-rect", 0.1 * (i + 1), i));
  for (int i = 0; i < 6; ++i) ASSERT_EQ((i % 2 ? a : b)->Insert(results[i]), "");
  ASSERT_EQ(a->Insert(results[1]), "");  // a duplicate row merges once
  ASSERT_EQ(all->MergeFrom((dir.path / "a.db").string()), "");
  ASSERT_EQ(all->MergeFrom((dir.path / "b.db").string()), "");
  const auto rows = all->All();
  ASSERT_EQ(rows.size(), 6u);
  for (const JobResult& r : results) EXPECT_TRUE(all->Has(r.id));
  EXPECT_NE(all->MergeFrom((dir.path / "missing.db").string()), "");
}

TEST(ResultStore, UnwritableLocationIsAClearError) {
  auto [store, error] = ResultStore::Open("/proc/shimmer-no/r.db");
  EXPECT_FALSE(store);
  EXPECT_NE(error.find("/proc/shimmer-no/r.db"), std::string::npos) << error;
}

}  // namespace
}  // namespace shimmer::experiments

#include "report.h"

namespace shimmer::experiments {
namespace {

TEST(Report, ParetoFrontKeepsOnlyUndominatedPoints) {
  // (cost, error): b dominates c; a is cheapest; d is most accurate; e ties a's cost but is worse.
  const std::vector<double> cost{1, 2, 3, 5, 1};
  const std::vector<double> error{10, 5, 6, 1, 11};
  EXPECT_EQ(ParetoFront(cost, error), (std::vector<int>{0, 1, 3}));
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
  ASSERT_EQ(WriteReport(rows, "t", (dir.path / "rep").string(), &warnings), "");
  std::ifstream csv(dir.path / "rep" / "report.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header,
            "scene,material,camera,variant,params,derivatives,tv_ratio,tv_err,energy_bias,temporal_diff_err,relmse,"
            "flicker_index,ms_per_frame");
  int lines = 0;
  for (std::string l; std::getline(csv, l);) ++lines;
  EXPECT_EQ(lines, 3);
  std::ifstream md(dir.path / "rep" / "report.md");
  std::string text((std::istreambuf_iterator<char>(md)), {});
  EXPECT_NE(text.find("| tk19 fp_max=1 |"), std::string::npos) << text;
  EXPECT_NE(text.find("## Summary"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir.path / "rep" / "sphere___ggx_0_02___orbit___quad_pareto_tv_err.gp"));
  EXPECT_TRUE(fs::exists(dir.path / "rep" / "sphere___ggx_0_02___orbit___quad_pareto_relmse.gp"));
  EXPECT_TRUE(fs::exists(dir.path / "rep" / "sphere___ggx_0_02___orbit___quad_spectra.gp"));
  EXPECT_NE(WriteReport({}, "t", (dir.path / "empty").string(), &warnings), "");
}

}  // namespace
}  // namespace shimmer::experiments
