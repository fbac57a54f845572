// A shot's reference shown converged, not assumed (DESIGN.md, Trust): the
// metrics of `none` against the reference must barely move when the
// reference doubles its samples per axis. Here the check of one shot and the
// run's pass over the shots the store lacks.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "runner_parts.h"
#include "shimmer/core/sequence_file.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/metrics/metrics_report.h"

namespace shimmer::experiments {

namespace fs = std::filesystem;

namespace {

// The seed of the check's reference (any but the shot reference's 0).
constexpr std::uint32_t kCheckSeed = 0x2c4ec5u;

// tv_err below this share of tv_ref counts as no flicker (see CheckShot).
constexpr double kNegligibleTvErr = 1e-3;

// From zero to anything is as large a change as there is (finite: the store's JSON has no infinity).
double RelativeChange(double check, double base) {
  if (base == 0) return check == 0 ? 0 : std::numeric_limits<double>::max();
  return std::abs(check / base - 1);
}

// Reference pixels (summed over frames) left above the adaptive tolerance.
long long UnconvergedPixels(const fs::path& dir) {
  auto sequence = ReadSequenceFile(dir / "sequence.json");
  if (!sequence) return 0;
  long long n = 0;
  for (const SequenceFrame& f : sequence->frames) n += f.unconverged_pixels.value_or(0);
  return n;
}

// The reference's frames 0, k, 2k, ... as a sequence of their own in `dir`
// (a sequence.json naming the reference's files): nothing copied, nothing
// rendered again.
Status WriteFrameSubset(const fs::path& reference, int stride, const fs::path& dir) {
  auto sequence = ReadSequenceFile(reference / "sequence.json");
  if (!sequence) return sequence.failure();
  SequenceFile subset = *sequence;
  subset.frames.clear();
  for (std::size_t i = 0; i < sequence->frames.size(); i += stride) {
    SequenceFrame f = sequence->frames[i];
    f.file = fs::absolute(reference / f.file).string();
    subset.frames.push_back(f);
  }
  subset.frame_count = static_cast<int>(subset.frames.size());
  if (subset.fps) subset.fps = *subset.fps / stride;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Status::Failure(dir.string() + ": cannot create the folder: " + ec.message(), ErrorCode::kIo);
  return WriteSequenceFile(dir / "sequence.json", subset);
}

}  // namespace

void JudgeConvergence(ShotCheck& c) {
  // The reference's noise F adds to its own temporal variance as it does to
  // tv_err (below): tv_ref - F is the noise-free estimate. A sparkly
  // reference (glints) keeps F at 15-40 % of tv_ref at 8 x 8 samples, and
  // tv_ref then falls by as much when the samples double while tv_ref - F
  // holds still to 1 %.
  c.d_tv_ref = std::min(RelativeChange(c.tv_ref_check, c.tv_ref),
                        RelativeChange(std::max(c.tv_ref_check - c.tv_err_noise_check, 0.0),
                                       std::max(c.tv_ref - c.tv_err_noise, 0.0)));
  c.d_energy_bias = std::abs(c.energy_bias_check - c.energy_bias);
  // A tv_err far below the reference's own temporal variance is flicker no
  // filter can remove and no viewer can see (none already matches the
  // reference); its relative change is measured against that floor, else a
  // near-zero tv_err made only of reference noise fails the check forever.
  const double tv_err_floor = kNegligibleTvErr * c.tv_ref;
  auto change = [tv_err_floor](double at_n, double at_2n) {
    return at_n >= tv_err_floor ? RelativeChange(at_2n, at_n) : std::abs(at_2n - at_n) / tv_err_floor;
  };
  // Each reference's own noise F (mean stderr.Y^2) may add to tv_err:
  // doubling the samples per axis divides F by four or more, which is the
  // noise converging, not the reference's mean. A Monte Carlo reference (SG
  // lights) keeps such noise where `none` matches it closely, and there tv_err
  // falls with F; tv_err - F, the noise-free tv_err's estimate, then holds
  // still. Where the replicates' spread overstates what reaches tv_err
  // (measured: rough delta-lit spheres, F ~ tv_err at N, tv_err unchanged at
  // 2N), tv_err itself holds still. Either is convergence.
  const double raw = change(c.tv_err, c.tv_err_check);
  const double denoised =
      change(std::max(c.tv_err - c.tv_err_noise, 0.0), std::max(c.tv_err_check - c.tv_err_noise_check, 0.0));
  c.d_tv_err = std::min(raw, denoised);
  // A glint reference's sparkles are what its sparkle statistics compare
  // with: where a pixel holds thousands of microdetails and the reference
  // a few hundred samples, its own noise makes sparkles of its own
  // (glint-plane at 8 x 8 x 4 samples: 1.7 times the far rows' sparkles at
  // 16 x 16), and their count falls as the samples grow.
  // Not measured (both 0): no change.
  c.d_sparkle_count = RelativeChange(c.sparkle_count_check, c.sparkle_count);
  c.converged = c.d_energy_bias <= c.tol_energy && c.d_tv_ref <= c.tol_tv && c.d_tv_err <= c.tol_tv &&
                c.d_sparkle_count <= c.tol_tv;
}

Result<ShotCheck> CheckShot(const Job& shot_job, const RunOptions& options) {
  const Job job = AsNone(shot_job);
  if (Status s = EnsureReference(job, options); !s) return s.failure();

  ShotCheck c;
  c.reference_id = ReferenceId(job);
  c.scene = job.scene;
  c.material = job.material;
  c.camera = job.camera;
  c.spp = job.reference.spp;
  c.tolerance = job.reference.tolerance;
  // Twice the samples per axis; an adaptive reference goes one level finer
  // (half the tolerance: four times the samples where they are needed).
  // The check's frames: the camera path at 1/k of its frame rate is its
  // frames 0, k, 2k, ... (CameraAt depends on frame / fps alone).
  const int stride = std::clamp(job.reference.converge.frame_stride, 1, job.frames);
  c.frame_stride = stride;
  Job check = job;
  check.frames = (job.frames + stride - 1) / stride;
  check.fps = job.fps / stride;
  check.reference.spp = std::min(2 * job.reference.spp, render::kMaxReferenceSpp);
  check.reference.tolerance = job.reference.tolerance / 2;
  c.check_spp = check.reference.spp;
  c.check_tolerance = check.reference.tolerance;
  c.tol_energy = job.reference.converge.energy;
  c.tol_tv = job.reference.converge.tv;
  if (c.check_spp == c.spp && c.tolerance == 0)
    return Result<ShotCheck>::Failure("reference.spp: " + std::to_string(c.spp) +
                                      " leaves no room to check convergence at twice the samples per axis (at most " +
                                      std::to_string(render::kMaxReferenceSpp) + ")");

  const fs::path work(options.work_dir);
  const fs::path ref_dir = ReferenceDirectory(job, options);
  // Named by the frames they hold: kept frames (--keep-frames) of a check
  // on other frames are not taken for these.
  const std::string tag = (stride > 1 ? "every" + std::to_string(stride) + "-" : "") + c.reference_id;
  const fs::path check_dir = work / ("check-" + tag);
  const fs::path none_dir = work / ("none-" + tag);
  auto reference_settings = ReferenceSettings(check, options);
  if (!reference_settings) return reference_settings.failure();
  // An independent estimate: with the reference's own seed, sample k of a
  // pixel takes the same jitter at N and 2N, and the two errors partly
  // cancel in the comparison.
  reference_settings->seed = kCheckSeed;
  if (auto r = RenderInto(*reference_settings, check_dir); !r) return Prefixed("check reference", r.failure());
  auto none_settings = JobSettings(check, options);
  if (!none_settings) return none_settings.failure();
  if (auto r = RenderInto(*none_settings, none_dir); !r) return r.failure();
  const fs::path subset_dir = work / ("subset-" + tag);
  const fs::path ref_subset = stride > 1 ? subset_dir / "sequence.json" : ref_dir;
  if (stride > 1)
    if (Status s = WriteFrameSubset(ref_dir, stride, subset_dir); !s) return s.failure();

  // Both measured over the same pixels: the region of the shot's own
  // reference, as the jobs are measured.
  auto at_n = MeasureAgainst(job, none_dir, ref_subset, {});
  if (!at_n) return at_n.failure();
  const fs::path mask = check_dir / "region.png";
  cv::Mat region = at_n->region_mask * 255;
  if (!cv::imwrite(mask.string(), region))
    return Result<ShotCheck>::Failure(mask.string() + ": cannot write the region mask", ErrorCode::kIo);
  auto at_2n = MeasureAgainst(job, none_dir, check_dir, mask);
  if (!at_2n) return at_2n.failure();

  c.tv_ref = at_n->tv_ref.value_or(0);
  c.tv_ref_check = at_2n->tv_ref.value_or(0);
  c.energy_bias = at_n->energy_bias.value_or(0);
  c.energy_bias_check = at_2n->energy_bias.value_or(0);
  c.tv_err = at_n->tv_err.value_or(0);
  c.tv_err_check = at_2n->tv_err.value_or(0);
  c.tv_err_noise = c.tv_err * at_n->tv_err_floor.value_or(0);
  c.tv_err_noise_check = c.tv_err_check * at_2n->tv_err_floor.value_or(0);
  if (at_n->sparkles && at_n->sparkles->reference && at_2n->sparkles && at_2n->sparkles->reference) {
    c.sparkle_count = at_n->sparkles->reference->mean_count;
    c.sparkle_count_check = at_2n->sparkles->reference->mean_count;
  }
  c.unconverged_pixels = UnconvergedPixels(ref_dir);
  JudgeConvergence(c);
  std::error_code ec;
  fs::remove_all(none_dir, ec);
  if (stride > 1) fs::remove_all(subset_dir, ec);
  if (!options.keep_frames) fs::remove_all(check_dir, ec);
  return c;
}

// One check per shot (reference id) that the store lacks, on `options.jobs`
// workers. Shots are dealt to shards by index, as benchmark batches are, so
// a sharded run checks each shot once, not once per shard.
Status CheckShots(const std::vector<Job>& all_jobs, const RunOptions& options, ResultStore& store,
                  RunProgress* progress, RunSummary* summary, std::chrono::steady_clock::time_point start) {
  std::vector<Job> shots;
  std::set<std::string> seen;
  int index = 0;
  for (const Job& job : all_jobs) {
    if (job.external) continue;  // its reference is the user's, rendered by no one here
    if (!seen.insert(ReferenceId(job)).second) continue;
    if (index++ % options.shard_count != options.shard_index) continue;
    auto has = store.HasShot(ReferenceId(job));
    if (!has) return has.failure();
    if (!*has) shots.push_back(job);
  }
  std::mutex mutex;
  std::atomic<std::size_t> next{0};
  std::optional<Error> error;
  OnEachLane(options, [&](const RunOptions& on_lane) {
    for (std::size_t k = next++; k < shots.size(); k = next++) {
      const Job& job = shots[k];
      const std::string what = job.scene + " " + job.material + " " + job.camera;
      auto check = CheckShot(job, on_lane);
      std::lock_guard<std::mutex> lock(mutex);
      if (error) return;
      if (!check) {
        error = Prefixed("reference check of " + what, check.failure());
        return;
      }
      if (Status s = store.InsertShot(*check); !s) {
        error = s.failure();
        return;
      }
      ++summary->shots_checked;
      if (!check->converged) ++summary->shots_unconverged;
      progress->current = "reference check " + std::to_string(summary->shots_checked) + "/" +
                          std::to_string(shots.size()) + ": " + what + (check->converged ? "" : " (unconverged)");
      progress->elapsed_s = SecondsSince(start);
      progress->eta_s = 0;
      if (options.progress) options.progress(*progress);
    }
  });
  if (error) return Status(*error);
  return Ok();
}

}  // namespace shimmer::experiments
