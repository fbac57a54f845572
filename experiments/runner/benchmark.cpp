// Cost as a benchmark, not a by-product (DESIGN.md, Trust): the per-job GPU
// time of small metric renders on shared cores swings by 2x between runs,
// so costs come from dedicated renders at a benchmark size, every variant of
// a batch interleaved repetition by repetition (a slow spell of the machine
// then hits all of them alike), after a warm-up frame that takes the JIT.
// Each ratio to `none` is the Hodges-Lehmann estimate of the paired
// per-repetition log ratios with a Wilcoxon signed-rank 95 % interval:
// lavapipe's frame times carry rare slow frames (5-10 % of a frame's time
// on an idle 2-core machine, far more under load), which widen a Student-t
// interval by their square and a rank interval by one rank. A variant is
// timed in rounds until its own interval is within the spec's precision
// (±3 % by default) or the repetition cap is reached; `none` is timed in
// every repetition that times any variant, so that the noisy ratios (short
// frames beside a long `none`) get the repetitions and the precise ones stop
// early. The order of the variants reverses every repetition (ABBA), so a
// drift within a repetition does not favour the first. Beside the times,
// the kernel's static instruction counts: a cost that does not depend on
// the device.
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "runner_parts.h"
#include "shimmer/experiments/runner.h"

namespace shimmer::experiments {

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}


}  // namespace

int SignedRankCriticalRank(int n) {
  if (n < 6) return 0;
  const long long m = static_cast<long long>(n) * (n + 1) / 2;
  if (n > 200) {
    const double sd = std::sqrt(static_cast<double>(n) * (n + 1) * (2.0 * n + 1) / 24);
    return static_cast<int>(std::max(1.0, std::floor(m / 2.0 - 1.959964 * sd)));
  }
  // ways[s]: the subsets of the ranks 1..n whose sum is s (the signed-rank
  // statistic's null distribution times 2^n); k is the largest rank with
  // P(T <= k - 1) <= 2.5 %.
  std::vector<double> ways(static_cast<std::size_t>(m) + 1, 0.0);
  ways[0] = 1;
  for (int r = 1; r <= n; ++r)
    for (long long s = m; s >= r; --s) ways[s] += ways[s - r];
  const double total = std::ldexp(1.0, n);
  double below = 0;
  int k = 0;
  while (k < m && (below + ways[k]) / total <= 0.025) below += ways[k++];
  return k;
}

RatioEstimate PairedRatio(const std::vector<double>& test_ms, const std::vector<double>& none_ms) {
  RatioEstimate r;
  std::vector<double> d;
  for (std::size_t i = 0; i < test_ms.size() && i < none_ms.size(); ++i)
    if (test_ms[i] > 0 && none_ms[i] > 0) d.push_back(std::log(test_ms[i] / none_ms[i]));
  r.n = static_cast<int>(d.size());
  if (d.empty()) return r;
  // The Walsh averages (d_i + d_j) / 2, i <= j.
  std::vector<double> walsh;
  walsh.reserve(d.size() * (d.size() + 1) / 2);
  for (std::size_t i = 0; i < d.size(); ++i)
    for (std::size_t j = i; j < d.size(); ++j) walsh.push_back(0.5 * (d[i] + d[j]));
  std::sort(walsh.begin(), walsh.end());
  r.ratio = std::exp(Median(walsh));
  if (const int k = SignedRankCriticalRank(r.n); k > 0) {
    r.lo = std::exp(walsh[k - 1]);
    r.hi = std::exp(walsh[walsh.size() - k]);
  }
  return r;
}

std::vector<BenchmarkBatch> BenchmarkBatches(const std::vector<Job>& jobs) {
  std::vector<BenchmarkBatch> batches;
  for (const Job& job : jobs) {
    if (job.external) continue;  // its cost is the user's, if they gave one
    // A job is timed in the batch of its own derivative source, the one its
    // row's cost is joined on. A variant that reads no derivatives has one
    // job, under the first source (ExpandJobs), so it is timed once, not
    // again under every other source for a cost no row would read; each
    // batch has its own `none`, the base of its ratios.
    auto it = std::find_if(batches.begin(), batches.end(), [&](const BenchmarkBatch& b) {
      return b.scene == job.scene && b.derivatives == job.derivatives;
    });
    if (it == batches.end()) {
      batches.push_back({job.scene, job.derivatives, {AsNone(job)}});
      it = batches.end() - 1;
    }
    const bool present = std::any_of(it->jobs.begin(), it->jobs.end(), [&](const Job& j) {
      return j.variant == job.variant && j.params == job.params;
    });
    if (present) continue;
    Job member = it->jobs.front();  // the batch's material, camera and motion
    member.variant = job.variant;
    member.params = job.params;
    member.variant_file = job.variant_file;
    member.variant_hash = job.variant_hash;
    it->jobs.push_back(member);
  }
  return batches;
}

std::string BenchmarkKernels(const BenchmarkBatch& batch, std::size_t k) {
  auto kernel = [](const Job& job) {
    auto sources = SourcesOf(job);
    return sources ? sources->test.kernel : std::string("unresolved");
  };
  // "signed-rank-1": the ABBA-interleaved paired ratios with signed-rank
  // intervals, each variant timed until its own is precise; costs timed the
  // older ways are timed again.
  return Fnv1a64Hex(kernel(batch.jobs[k]) + '\0' + kernel(batch.jobs.front()) + '\0' + "signed-rank-1");
}

Result<std::vector<BenchmarkCost>> RunBenchmark(const BenchmarkBatch& batch, const BenchmarkOptions& bench,
                                                const RunOptions& options) {
  using R = Result<std::vector<BenchmarkCost>>;
  std::vector<std::unique_ptr<render::Renderer>> renderers;
  for (const Job& job : batch.jobs) {
    auto settings = JobSettings(job, options);
    if (!settings) return settings.failure();
    settings->width = bench.width;
    settings->height = bench.height;
    auto renderer = render::Renderer::Create(*settings);
    if (!renderer) return Prefixed("benchmark of " + job.variant, renderer.failure());
    // Warm-up: lavapipe compiles the pipeline on its first dispatch.
    if (auto warm = (*renderer)->RenderFrame(0); !warm) return Prefixed("benchmark of " + job.variant, warm.failure());
    renderers.push_back(std::move(*renderer));
  }
  std::vector<shading::InstructionCensus> census;
  for (const Job& job : batch.jobs) {
    auto settings = JobSettings(job, options);
    auto counted = settings ? render::CountKernelInstructions(*settings)
                            : Result<shading::InstructionCensus>(settings.failure());
    if (!counted) return Prefixed("instruction counts of " + job.variant, counted.failure());
    census.push_back(*counted);
  }
  // ms[k]: variant k's times; paired[k]: `none`'s time in the same
  // repetitions (for k = 0, every repetition's).
  const std::size_t count = renderers.size();
  std::vector<std::vector<double>> ms(count), paired(count);
  std::vector<bool> timing(count, true);
  const int frames = batch.jobs.front().frames;
  const int round = std::max(bench.repetitions, 2);
  int reps = 0;
  auto any_timing = [&] { return std::find(timing.begin() + 1, timing.end(), true) != timing.end(); };
  while (reps < bench.max_repetitions && (reps == 0 || any_timing())) {
    for (int r = 0; r < round && reps < bench.max_repetitions; ++r, ++reps) {
      // Frames spread over the path by the golden ratio, the same for every variant.
      const int frame = static_cast<int>(std::fmod(reps * 0.6180339887, 1.0) * frames) % std::max(frames, 1);
      std::vector<double> now(count, 0.0);
      for (std::size_t i = 0; i < count; ++i) {
        const std::size_t k = reps % 2 ? count - 1 - i : i;
        if (!timing[k]) continue;
        auto f = renderers[k]->RenderFrame(frame);
        if (!f) return Prefixed("benchmark of " + batch.jobs[k].variant, f.failure());
        now[k] = f->gpu_ms;
      }
      for (std::size_t k = 0; k < count; ++k)
        if (timing[k]) ms[k].push_back(now[k]), paired[k].push_back(now[0]);
    }
    for (std::size_t k = 1; k < count; ++k)
      if (timing[k] && PairedRatio(ms[k], paired[k]).Within(bench.precision)) timing[k] = false;
  }
  std::vector<BenchmarkCost> costs;
  const double none_ms = Median(ms.front());
  for (std::size_t k = 0; k < renderers.size(); ++k) {
    const Job& job = batch.jobs[k];
    BenchmarkCost c;
    c.scene = batch.scene;
    c.derivatives = batch.derivatives;
    c.variant = job.variant;
    c.params = job.params;
    c.material = job.material;
    c.camera = job.camera;
    c.width = bench.width;
    c.height = bench.height;
    c.repetitions = static_cast<int>(ms[k].size());
    c.median_ms = Median(ms[k]);
    c.min_ms = *std::min_element(ms[k].begin(), ms[k].end());
    c.max_ms = *std::max_element(ms[k].begin(), ms[k].end());
    c.none_median_ms = none_ms;
    const RatioEstimate ratio =
        k == 0 ? RatioEstimate{1, 1, 1, static_cast<int>(ms[0].size())} : PairedRatio(ms[k], paired[k]);
    c.ratio_to_none = ratio.ratio;
    c.ratio_lo = ratio.lo;
    c.precision = bench.precision;
    c.ratio_hi = ratio.hi;
    c.kernel = census[k];
    c.none_kernel = census.front();
    c.core = BenchmarkKernels(batch, k);
    c.device = renderers[k]->device_name();
    c.driver = renderers[k]->device_driver();
    costs.push_back(std::move(c));
  }
  if (costs.empty()) return R::Failure("benchmark: an empty batch");
  return costs;
}

namespace {

// The name of the device the benchmarks run on, as the store records it.
std::string BenchmarkDevice(const RunOptions& options) {
  auto devices = render::ListDevices();
  if (devices)
    for (const auto& d : *devices)
      if (d.name.find(options.device) != std::string::npos) return d.name;
  return "";
}

// The members of the batch to time (indices; `none`, 0, first): all of
// them when any lacks a cost timed on this device with the kernels it runs
// now (a kernel change moves costs as it moves ids); else `none` and the
// variants whose cost's interval is wider than the precision after fewer
// repetitions than the cap (a raised cap times them again); else none.
std::vector<std::size_t> BenchmarkMembersToTime(const BenchmarkBatch& batch, const BenchmarkOptions& bench,
                                                const std::string& device, const std::vector<BenchmarkCost>& existing) {
  std::vector<std::size_t> imprecise;
  for (std::size_t k = 0; k < batch.jobs.size(); ++k) {
    const Job& job = batch.jobs[k];
    const std::string kernels = BenchmarkKernels(batch, k);
    const auto cost = std::find_if(existing.begin(), existing.end(), [&](const BenchmarkCost& c) {
      return c.scene == batch.scene && c.derivatives == batch.derivatives && c.variant == job.variant &&
             c.params == job.params && c.width == bench.width && c.height == bench.height && c.device == device &&
             c.core == kernels;
    });
    if (cost == existing.end()) {
      std::vector<std::size_t> all(batch.jobs.size());
      for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
      return all;
    }
    const RatioEstimate ratio{cost->ratio_to_none, cost->ratio_lo, cost->ratio_hi, cost->repetitions};
    if (k > 0 && !ratio.Within(bench.precision) && cost->repetitions < bench.max_repetitions) imprecise.push_back(k);
  }
  if (!imprecise.empty()) imprecise.insert(imprecise.begin(), 0);
  return imprecise;
}

}  // namespace

// Times this shard's batches (dealt by index, so each is timed once, whole)
// that the store lacks.
Status RunBenchmarks(const std::vector<Job>& all_jobs, const BenchmarkOptions& bench, const RunOptions& options,
                     ResultStore& store, RunProgress* progress, RunSummary* summary,
                     std::chrono::steady_clock::time_point start) {
  auto existing = store.Benchmarks();
  if (!existing) return existing.failure();
  const std::string device = BenchmarkDevice(options);
  const std::vector<BenchmarkBatch> batches = BenchmarkBatches(all_jobs);
  for (std::size_t b = options.shard_index; b < batches.size(); b += options.shard_count) {
    const std::vector<std::size_t> members = BenchmarkMembersToTime(batches[b], bench, device, *existing);
    if (members.empty()) continue;
    BenchmarkBatch batch{batches[b].scene, batches[b].derivatives, {}};
    for (std::size_t k : members) batch.jobs.push_back(batches[b].jobs[k]);
    progress->current = "benchmark " + batch.scene + " " + batch.derivatives + " (" +
                        std::to_string(batch.jobs.size()) + " variants at " + std::to_string(bench.width) + "x" +
                        std::to_string(bench.height) + ")";
    progress->elapsed_s = SecondsSince(start);
    if (options.progress) options.progress(*progress);
    auto costs = RunBenchmark(batch, bench, options);
    if (!costs) return costs.failure();
    if (Status s = store.InsertBenchmarks(*costs); !s) return s;
    ++summary->benchmarks;
  }
  return Ok();
}

}  // namespace shimmer::experiments
