#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "job_results.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/experiments/spec.h"
#include "temp_dir.h"

namespace shimmer::experiments {
namespace {

namespace fs = std::filesystem;

using shimmer::testing::TempDir;
using testing::MakeResult;

// A store from before fits per normal map (fits keyed by variant, param and
// material) opens with its fit rows kept, and then holds one row per map.
TEST(ResultStore, FitsFromBeforeMapsAreKeptAndKeyedByMap) {
  TempDir dir;
  const std::string path = (dir.path() / "old.db").string();
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "CREATE TABLE fits (variant TEXT NOT NULL, param TEXT NOT NULL, material TEXT NOT NULL, "
                         "value REAL, j_train REAL, j_validate REAL, result TEXT NOT NULL, "
                         "finished_at TEXT DEFAULT (datetime('now')), PRIMARY KEY (variant, param, material));"
                         "INSERT INTO fits (variant, param, material, value, j_train, j_validate, result) "
                         "VALUES ('lean', 'nm_scale', 'ggx:0.05', 0.5, 1, 2, '{\"value\": 0.5}');",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);

  auto opened = ResultStore::Open(path);
  ASSERT_TRUE(opened) << opened.error();
  ResultStore& store = **opened;
  auto rows = store.Fits();
  ASSERT_TRUE(rows) << rows.error();
  ASSERT_EQ(rows->size(), 1u);
  EXPECT_EQ((*rows)[0]["value"], 0.5);
  for (const char* map : {"bumps", "ridges"})
    ASSERT_TRUE(store.InsertFit("lean", "nm_scale", "ggx:0.05", map, 2, 1, 1, {{"map", map}}));
  // The same key again replaces its row.
  ASSERT_TRUE(store.InsertFit("lean", "nm_scale", "ggx:0.05", "ridges", 3, 1, 1, {{"map", "ridges"}, {"again", 1}}));
  rows = store.Fits();
  ASSERT_EQ(rows->size(), 3u);
  EXPECT_EQ((*rows)[0]["value"], 0.5);  // map "" sorts first
  EXPECT_EQ((*rows)[1]["map"], "bumps");
  EXPECT_EQ((*rows)[2]["again"], 1);
}

TEST(ResultStore, InsertThenFindAndReadBack) {
  TempDir dir;
  auto opened = ResultStore::Open((dir.path() / "r.db").string());
  ASSERT_TRUE(opened) << opened.error();
  std::unique_ptr<ResultStore> store = std::move(*opened);
  JobResult r = MakeResult("k16-beckmann-rect", 0.5, 3.0);
  r.device = "test device";
  r.driver = "test driver 1.0";
  auto draws = std::make_shared<metrics::BootstrapDraws>();
  draws->key = 0x1234'5678'9abc'def0ULL;
  draws->tv_err = {{1.5f, 2.5f}, {1.25f, 2.25f}, {1.f, 2.f}};
  draws->relmse = {{0.5f, 0.25f}, {0.125f, 0.f}, {3.f, 4.f}};
  r.draws = draws;
  EXPECT_FALSE(*store->Has(r.id));
  ASSERT_TRUE(store->Insert(r));
  EXPECT_TRUE(*store->Has(r.id));
  const auto rows = *store->All();
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].device, "test device");
  EXPECT_EQ(rows[0].driver, "test driver 1.0");
  EXPECT_EQ(rows[0].job.ToJson(), r.job.ToJson());
  EXPECT_EQ(rows[0].metrics, r.metrics);
  EXPECT_DOUBLE_EQ(rows[0].gpu_ms_per_frame, 1.5);
  // The bootstrap draws come back as they went in.
  ASSERT_TRUE(rows[0].draws);
  EXPECT_EQ(rows[0].draws->key, draws->key);
  EXPECT_EQ(rows[0].draws->tv_err.blocks_only, draws->tv_err.blocks_only);
  EXPECT_EQ(rows[0].draws->relmse.tiles_only, draws->relmse.tiles_only);
  // Reopening sees the same row: it was committed.
  store.reset();
  auto again = ResultStore::Open((dir.path() / "r.db").string(), ResultStore::Mode::kReadOnly);
  ASSERT_TRUE(again) << again.error();
  EXPECT_TRUE(*(*again)->Has(r.id));
}

TEST(ResultStore, MergedShardsEqualOneStore) {
  TempDir dir;
  const std::string a = (dir.path() / "a.db").string(), b = (dir.path() / "b.db").string();
  const std::string all = (dir.path() / "all.db").string();
  std::vector<JobResult> results;
  for (int i = 0; i < 6; ++i) results.push_back(MakeResult("k16-beckmann-rect", 0.1 * (i + 1), i));
  auto draws = std::make_shared<metrics::BootstrapDraws>();
  draws->key = 42;
  draws->tv_err = draws->relmse = {{1.f, 2.f, 3.f}, {1.f, 2.f, 3.f}, {1.f, 2.f, 3.f}};
  results[3].draws = draws;
  {
    auto sa = ResultStore::Open(a);
    auto sb = ResultStore::Open(b);
    ASSERT_TRUE(sa && sb);
    for (int i = 0; i < 6; ++i) {
      results[i].device = i % 2 ? "machine A" : "machine B";
      ASSERT_TRUE((i % 2 ? *sa : *sb)->Insert(results[i]));
    }
    ASSERT_TRUE((*sa)->Insert(results[1]));  // a duplicate row merges once
  }
  auto merged = MergeStores({a, b}, all);
  ASSERT_TRUE(merged) << merged.error();
  EXPECT_EQ(*merged, 6u);
  auto store = ResultStore::Open(all, ResultStore::Mode::kReadOnly);
  ASSERT_TRUE(store);
  const auto rows = *(*store)->All();
  ASSERT_EQ(rows.size(), 6u);
  // Each row says which machine computed it.
  for (const JobResult& r : results) {
    auto row = std::find_if(rows.begin(), rows.end(), [&](const JobResult& x) { return x.id == r.id; });
    ASSERT_NE(row, rows.end());
    EXPECT_EQ(row->device, r.device);
    // Bootstrap draws merge with their row; rows without stay without.
    ASSERT_EQ(bool(row->draws), bool(r.draws));
    if (r.draws) {
      EXPECT_EQ(row->draws->tv_err.joint, r.draws->tv_err.joint);
    }
  }
}

// A merge is all or nothing: an input that fails after others were read
// leaves the output as it was (here: not there at all).
TEST(ResultStore, MergeWithABadInputChangesNothing) {
  TempDir dir;
  const std::string a = (dir.path() / "a.db").string(), all = (dir.path() / "all.db").string();
  {
    auto sa = ResultStore::Open(a);
    ASSERT_TRUE(sa);
    ASSERT_TRUE((*sa)->Insert(MakeResult("none", 0, 1)));
  }
  const std::string junk = (dir.path() / "junk.db").string();
  std::ofstream(junk) << "not a database";
  for (const std::string& bad : {(dir.path() / "missing.db").string(), junk}) {
    auto merged = MergeStores({a, bad}, all);
    ASSERT_FALSE(merged);
    EXPECT_NE(merged.error().find(bad), std::string::npos) << merged.error();
    EXPECT_FALSE(std::filesystem::exists(all)) << bad;
  }
  // And an existing output keeps exactly its rows.
  ASSERT_TRUE(MergeStores({a}, all));
  auto merged = MergeStores({a, junk}, all);
  ASSERT_FALSE(merged);
  auto store = ResultStore::Open(all, ResultStore::Mode::kReadOnly);
  ASSERT_TRUE(store);
  EXPECT_EQ((*store)->All()->size(), 1u);
}

// report reads a store without writing to it: no new tables, no WAL switch,
// not even on a file the process may not write.
TEST(ResultStore, ReadOnlyOpenLeavesTheFileUntouched) {
  TempDir dir;
  const std::string path = (dir.path() / "r.db").string();
  {
    auto s = ResultStore::Open(path);
    ASSERT_TRUE(s);
    ASSERT_TRUE((*s)->Insert(MakeResult("none", 0, 2)));
  }
  std::filesystem::remove(path + "-wal");
  std::filesystem::remove(path + "-shm");
  std::ifstream before_in(path, std::ios::binary);
  const std::string before((std::istreambuf_iterator<char>(before_in)), {});
  std::filesystem::permissions(path, std::filesystem::perms::owner_read, std::filesystem::perm_options::replace);
  {
    auto s = ResultStore::Open(path, ResultStore::Mode::kReadOnly);
    ASSERT_TRUE(s) << s.error();
    EXPECT_EQ((*s)->All()->size(), 1u);
  }
  std::ifstream after_in(path, std::ios::binary);
  const std::string after((std::istreambuf_iterator<char>(after_in)), {});
  EXPECT_EQ(before, after);
  EXPECT_FALSE(fs::exists(path + "-wal"));
  EXPECT_FALSE(fs::exists(path + "-shm"));
  std::filesystem::permissions(path, std::filesystem::perms::owner_all, std::filesystem::perm_options::replace);
  EXPECT_FALSE(ResultStore::Open((dir.path() / "missing.db").string(), ResultStore::Mode::kReadOnly));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "missing.db"));
}

TEST(ResultStore, SecondLockOnAStoreIsRefusedAtOnce) {
  TempDir dir;
  const std::string path = (dir.path() / "r.db").string();
  auto first = StoreLock::Acquire(path);
  ASSERT_TRUE(first) << first.error();
  auto second = StoreLock::Acquire(path);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().find("another shimmer process"), std::string::npos) << second.error();
  first->reset();
  EXPECT_TRUE(StoreLock::Acquire(path));
}

TEST(ResultStore, UnwritableLocationIsAClearError) {
  auto store = ResultStore::Open("/proc/shimmer-no/r.db");
  EXPECT_FALSE(store);
  EXPECT_NE(store.error().find("/proc/shimmer-no/r.db"), std::string::npos) << store.error();
}

}  // namespace
}  // namespace shimmer::experiments

namespace shimmer::experiments {
namespace {

TEST(ResultStore, ShotChecksAndBenchmarksJoinTheirRowsAndMerge) {
  TempDir dir;
  const std::string a = (dir.path() / "a.db").string(), all = (dir.path() / "all.db").string();
  JobResult tk = MakeResult("k16-beckmann-rect", 0.5, 3.0);
  tk.device = "gpu A";
  JobResult none = MakeResult("none", 0, 9.0);
  none.job.params.clear();
  none.id = JobId(none.job);
  none.device = "gpu A";
  ShotCheck shot;
  shot.reference_id = tk.reference_id;
  shot.scene = "sphere";
  shot.spp = 4;
  shot.check_spp = 8;
  // The store re-judges a shot from its measurements: energy_bias moved by
  // 0.05 at twice the samples, beyond the 0.02 tolerance.
  shot.energy_bias = 0.10;
  shot.energy_bias_check = 0.15;
  shot.tv_ref = shot.tv_ref_check = 1;
  shot.tv_err = shot.tv_err_check = 0.5;
  shot.converged = true;
  BenchmarkCost cost;
  cost.scene = "sphere";
  cost.derivatives = "quad";
  cost.variant = "k16-beckmann-rect";
  cost.params = tk.job.params;
  cost.width = cost.height = 512;
  cost.median_ms = 3;
  cost.ratio_to_none = 1.5;
  BenchmarkCost other_device = cost;
  other_device.device = "gpu B";
  other_device.ratio_to_none = 7;
  cost.device = "gpu A";
  {
    auto store = ResultStore::Open(a);
    ASSERT_TRUE(store) << store.error();
    ASSERT_TRUE((*store)->Insert(tk));
    ASSERT_TRUE((*store)->Insert(none));
    EXPECT_FALSE(*(*store)->HasShot(shot.reference_id));
    ASSERT_TRUE((*store)->InsertShot(shot));
    EXPECT_TRUE(*(*store)->HasShot(shot.reference_id));
    ASSERT_TRUE((*store)->InsertBenchmarks({other_device, cost}));
  }
  auto merged = MergeStores({a}, all);
  ASSERT_TRUE(merged) << merged.error();
  for (const std::string& path : {a, all}) {
    auto store = ResultStore::Open(path, ResultStore::Mode::kReadOnly);
    ASSERT_TRUE(store) << store.error();
    auto rows = (*store)->All();
    ASSERT_TRUE(rows) << rows.error();
    ASSERT_EQ(rows->size(), 2u);
    for (const JobResult& r : *rows) {
      ASSERT_TRUE(r.shot) << path;  // both rows share the shot's reference
      EXPECT_FALSE(r.shot->converged);
      EXPECT_NEAR(r.shot->d_energy_bias, 0.05, 1e-12);
      EXPECT_EQ(r.shot->check_spp, 8);
      if (r.job.variant == "none") {
        EXPECT_FALSE(r.cost) << "no benchmark row for none";
      } else {
        ASSERT_TRUE(r.cost) << path;
        EXPECT_EQ(r.cost->device, "gpu A") << "the row's own device is preferred";
        EXPECT_DOUBLE_EQ(r.cost->ratio_to_none, 1.5);
      }
    }
    EXPECT_EQ((*store)->Benchmarks()->size(), 2u);
  }
}

// A store run with two shading cores: prune keeps the current core's rows
// (an external sequence's row among them only while its id is current), the
// checks they refer to and the costs this core timed;
// a dry run counts the same and changes nothing; a store with no row of the
// current core is refused untouched.
TEST(ResultStore, PruneRemovesOlderCoresRowsChecksAndCosts) {
  TempDir dir;
  const std::string path = (dir.path() / "s.db").string();
  JobResult current = MakeResult("tk19", 0.5, 3.0);
  JobResult old_a = current, old_b = MakeResult("none", 0, 1.0);
  old_a.core_version = "aaaa", old_a.id = "old-a", old_a.reference_id = "ref-old";
  old_b.core_version = "bbbb", old_b.id = "old-b", old_b.reference_id = "ref-old";
  JobResult external = MakeResult("engine", 0, 1.0);
  external.job.external = ExternalFrames{"t", "r", "th", "rh", 0, ""};
  external.job.derivatives = kExternalDerivatives;
  external.core_version = "aaaa", external.id = "ext", external.reference_id = "ref-ext";
  JobResult old_external = external;  // measured by an older metrics code
  old_external.id = "ext-old";
  ShotCheck kept_shot, old_shot;
  kept_shot.reference_id = current.reference_id;
  old_shot.reference_id = "ref-old";
  BenchmarkCost timed_now, timed_before;
  timed_now.scene = timed_before.scene = "sphere";
  timed_now.derivatives = timed_before.derivatives = "quad";
  timed_now.variant = "tk19", timed_before.variant = "none";
  timed_now.width = timed_now.height = timed_before.width = timed_before.height = 512;
  timed_now.device = timed_before.device = "dev";
  timed_now.core = "kernels-now", timed_before.core = "aaaa";
  {
    auto store = ResultStore::Open(path);
    ASSERT_TRUE(store) << store.error();
    for (const JobResult& r : {current, old_a, old_b, external, old_external}) ASSERT_TRUE((*store)->Insert(r));
    ASSERT_TRUE((*store)->InsertShot(kept_shot));
    ASSERT_TRUE((*store)->InsertShot(old_shot));
    ASSERT_TRUE((*store)->InsertBenchmarks({timed_now, timed_before}));
  }
  auto store = ResultStore::Open(path);
  ASSERT_TRUE(store);
  const std::set<std::string> current_jobs{current.id, external.id}, current_costs{"kernels-now"};
  const auto dry = (*store)->PruneStale(current_jobs, current_costs, /*dry_run=*/true);
  ASSERT_TRUE(dry) << dry.error();
  EXPECT_EQ(dry->jobs, 3u);
  EXPECT_EQ(dry->shots, 1u);
  EXPECT_EQ(dry->benchmarks, 1u);
  EXPECT_EQ(dry->kept_jobs, 2u);
  EXPECT_EQ(dry->kept_external, 1u);
  EXPECT_EQ((*store)->All()->size(), 5u);  // the dry run changed nothing
  // Refused when no job of the store is current: nothing removed.
  const auto refused = (*store)->PruneStale({"cccc"}, current_costs, false);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("nothing removed"), std::string::npos) << refused.error();
  EXPECT_EQ((*store)->All()->size(), 5u);
  const auto pruned = (*store)->PruneStale(current_jobs, current_costs, false);
  ASSERT_TRUE(pruned) << pruned.error();
  EXPECT_EQ(pruned->jobs, 3u);
  std::set<std::string> ids;
  const auto left = (*store)->All();
  ASSERT_TRUE(left);
  for (const JobResult& r : *left) ids.insert(r.id);
  EXPECT_EQ(ids, (std::set<std::string>{current.id, "ext"}));
  const auto shots = (*store)->Shots();
  ASSERT_EQ(shots->size(), 1u);
  EXPECT_EQ(shots->front().reference_id, current.reference_id);
  const auto costs = (*store)->Benchmarks();
  ASSERT_EQ(costs->size(), 1u);
  EXPECT_EQ(costs->front().variant, "tk19");
  // Again: nothing left to remove.
  const auto again = (*store)->PruneStale(current_jobs, current_costs, false);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->jobs + again->shots + again->benchmarks, 0u);
}

}  // namespace
}  // namespace shimmer::experiments
