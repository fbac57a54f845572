// Cost as a benchmark, not a by-product (DESIGN.md, Trust): the per-job GPU
// time of small metric renders on shared cores swings by 2x between runs,
// so costs come from dedicated renders at a benchmark size, every variant of
// a batch interleaved repetition by repetition (a slow spell of the machine
// then hits all of them alike), after a warm-up frame that takes the JIT.
// Each ratio to `none` is the geometric mean of the paired per-repetition
// ratios, with a Student-t 95 % interval on their logarithms; rounds of
// repetitions are added until every interval is within the spec's precision
// (±3 % by default) or the repetition cap is reached. The order of the
// variants reverses every repetition (ABBA), so a drift within a repetition
// does not favour the first. Beside the times, the kernel's static
// instruction counts: a cost that does not depend on the device.
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "runner_parts.h"
#include "shimmer/experiments/minimize.h"
#include "shimmer/experiments/runner.h"

namespace shimmer::experiments {

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}


}  // namespace

RatioEstimate PairedRatio(const std::vector<double>& test_ms, const std::vector<double>& none_ms) {
  RatioEstimate r;
  std::vector<double> d;
  for (std::size_t i = 0; i < test_ms.size() && i < none_ms.size(); ++i)
    if (test_ms[i] > 0 && none_ms[i] > 0) d.push_back(std::log(test_ms[i] / none_ms[i]));
  r.n = static_cast<int>(d.size());
  if (d.empty()) return r;
  double mean = 0;
  for (double x : d) mean += x;
  mean /= r.n;
  r.ratio = std::exp(mean);
  if (r.n < 2) return r;
  double ss = 0;
  for (double x : d) ss += (x - mean) * (x - mean);
  const double half = StudentT975(r.n - 1) * std::sqrt(ss / (r.n - 1) / r.n);
  r.lo = std::exp(mean - half);
  r.hi = std::exp(mean + half);
  return r;
}

std::vector<BenchmarkBatch> BenchmarkBatches(const std::vector<Job>& jobs) {
  std::vector<BenchmarkBatch> batches;
  std::set<std::string> derivative_sources;
  for (const Job& job : jobs)
    if (!job.external) derivative_sources.insert(job.derivatives);
  for (const Job& job : jobs) {
    if (job.external) continue;  // its cost is the user's, if they gave one
    // Variants that read no derivatives cost the same under every source:
    // they join every batch of their scene, so that each batch has its `none`.
    for (const std::string& derivatives : derivative_sources) {
      if (ReadsDerivatives(job.variant) && derivatives != job.derivatives) continue;
      auto it = std::find_if(batches.begin(), batches.end(), [&](const BenchmarkBatch& b) {
        return b.scene == job.scene && b.derivatives == derivatives;
      });
      if (it == batches.end()) {
        Job none = AsNone(job);
        none.derivatives = derivatives;
        batches.push_back({job.scene, derivatives, {none}});
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
  }
  return batches;
}

std::string BenchmarkKernels(const BenchmarkBatch& batch, std::size_t k) {
  auto kernel = [](const Job& job) {
    auto sources = SourcesOf(job);
    return sources ? sources->test.kernel : std::string("unresolved");
  };
  // "paired-2": the ABBA-interleaved paired ratios with intervals and
  // instruction counts; costs timed the older way are timed again.
  return Fnv1a64Hex(kernel(batch.jobs[k]) + '\0' + kernel(batch.jobs.front()) + '\0' + "paired-2");
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
  std::vector<std::vector<double>> ms(renderers.size());
  const int frames = batch.jobs.front().frames;
  const int round = std::max(bench.repetitions, 2);
  auto precise = [&] {
    for (std::size_t k = 1; k < renderers.size(); ++k)
      if (!PairedRatio(ms[k], ms.front()).Within(bench.precision)) return false;
    return true;
  };
  int reps = 0;
  do {
    for (int r = 0; r < round; ++r, ++reps) {
      // Frames spread over the path by the golden ratio, the same for every variant.
      const int frame = static_cast<int>(std::fmod(reps * 0.6180339887, 1.0) * frames) % std::max(frames, 1);
      for (std::size_t i = 0; i < renderers.size(); ++i) {
        const std::size_t k = reps % 2 ? renderers.size() - 1 - i : i;
        auto f = renderers[k]->RenderFrame(frame);
        if (!f) return Prefixed("benchmark of " + batch.jobs[k].variant, f.failure());
        ms[k].push_back(f->gpu_ms);
      }
    }
  } while (reps < bench.max_repetitions && !precise());
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
    c.repetitions = reps;
    c.median_ms = Median(ms[k]);
    c.min_ms = *std::min_element(ms[k].begin(), ms[k].end());
    c.max_ms = *std::max_element(ms[k].begin(), ms[k].end());
    c.none_median_ms = none_ms;
    const RatioEstimate ratio = k == 0 ? RatioEstimate{1, 1, 1, reps} : PairedRatio(ms[k], ms.front());
    c.ratio_to_none = ratio.ratio;
    c.ratio_lo = ratio.lo;
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

}  // namespace shimmer::experiments
