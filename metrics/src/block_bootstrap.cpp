#include "shimmer/metrics/block_bootstrap.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include <opencv2/core.hpp>

namespace shimmer::metrics {

namespace {

// Row layout: the scalars, then seven per-block sums: test and reference
// sums, the squared deviations of T, R and E from each pixel's temporal
// mean, the relMSE terms, and their weighted deviations from each pixel's
// weighted mean error.
enum Scalar { kPixels, kFlickerPower, kFlickerSegments, kT0, kR0, kScalars };
enum PerBlock { kST, kSR, kDT, kDR, kDE, kSQ, kDQ, kPerBlock };

// SplitMix64 (Steele, Lea & Flood 2014): the same draws on every platform,
// unlike std::uniform_int_distribution.
struct SplitMix64 {
  static constexpr std::uint64_t kGamma = 0x9e3779b97f4a7c15ULL;  // the state's step per draw
  std::uint64_t state;
  std::uint64_t Next() {
    std::uint64_t z = (state += kGamma);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  int Below(int n) { return static_cast<int>((static_cast<unsigned __int128>(Next()) * n) >> 64); }
};

double Quantile(std::vector<double> sorted, double q) {
  const double at = q * (sorted.size() - 1);
  const size_t i = static_cast<size_t>(at);
  if (i + 1 >= sorted.size()) return sorted.back();
  return sorted[i] + (at - i) * (sorted[i + 1] - sorted[i]);
}

// Unbiased sample variance (OpenCV's is the population one).
double Variance(const std::vector<double>& x) {
  if (x.size() < 2) return 0;
  cv::Scalar mean, stddev;
  cv::meanStdDev(x, mean, stddev);
  return stddev[0] * stddev[0] * static_cast<double>(x.size()) / static_cast<double>(x.size() - 1);
}

}  // namespace

int FrameBlockLength(int frames) {
  const int length = static_cast<int>(std::lround(std::cbrt(static_cast<double>(frames))));
  return std::clamp(length, 2, std::max(frames, 1));
}

TileBlockStatistics::TileBlockStatistics(std::vector<int> block_frames) : block_frames_(std::move(block_frames)) {
  stride_ = kScalars + kPerBlock * blocks();
}

int TileBlockStatistics::AddTile() {
  rows_.resize(rows_.size() + stride_, 0.0);
  return tiles() - 1;
}

void TileBlockStatistics::AddPixel(int tile, double t0, double r0, const float* sums, double flicker_power,
                                   double flicker_segments) {
  const int k_count = blocks();
  auto in = [&](CellSum kind, int k) { return double(sums[kind * k_count + k]); };
  double* row = rows_.data() + static_cast<size_t>(tile) * stride_;
  row[kPixels] += 1;
  row[kFlickerPower] += flicker_power;
  row[kFlickerSegments] += flicker_segments;
  row[kT0] += t0;
  row[kR0] += r0;
  // The pixel's temporal means (shifted) over the whole sequence: each
  // block's squared deviations are taken from them, so that a variance is a
  // sum over blocks (the linearised statistic the bootstrap resamples).
  double frames = 0, mean_t = 0, mean_r = 0, weight = 0, weighted_e = 0;
  for (int k = 0; k < k_count; ++k) {
    frames += block_frames_[k], mean_t += in(kSumT, k), mean_r += in(kSumR, k);
    weight += in(kWeight, k), weighted_e += in(kWeightedE, k);
  }
  mean_t /= frames;
  mean_r /= frames;
  const double mean_e = mean_t - mean_r;
  const double mean_we = weight > 0 ? weighted_e / weight : 0.0;  // the relMSE-weighted mean of E - e0
  double* per_block = row + kScalars;
  for (int k = 0; k < k_count; ++k) {
    const double n = block_frames_[k], st = in(kSumT, k), sr = in(kSumR, k), se = st - sr;
    per_block[kST * k_count + k] += st;
    per_block[kSR * k_count + k] += sr;
    per_block[kDT * k_count + k] += in(kSquareT, k) - 2 * mean_t * st + n * mean_t * mean_t;
    per_block[kDR * k_count + k] += in(kSquareR, k) - 2 * mean_r * sr + n * mean_r * mean_r;
    per_block[kDE * k_count + k] += in(kSquareE, k) - 2 * mean_e * se + n * mean_e * mean_e;
    per_block[kSQ * k_count + k] += in(kRelative, k);
    per_block[kDQ * k_count + k] +=
        in(kWeightedE2, k) - 2 * mean_we * in(kWeightedE, k) + mean_we * mean_we * in(kWeight, k);
  }
}

TileBlockStatistics::Estimates TileBlockStatistics::FromSums(const double* row,
                                                             const std::vector<int>& block_counts) const {
  const int k_count = blocks();
  auto count = [&](int k) { return block_counts.empty() ? 1.0 : double(block_counts[k]); };
  double frames = 0, all_frames = 0;
  for (int k = 0; k < k_count; ++k) frames += count(k) * block_frames_[k], all_frames += block_frames_[k];
  const double pixels = row[kPixels];
  const double* per_block = row + kScalars;
  auto linear = [&](int s) {
    double sum = 0;
    for (int k = 0; k < k_count; ++k) sum += count(k) * per_block[s * k_count + k];
    return sum;
  };
  // Mean over pixels and frames of the squared deviation from each pixel's
  // temporal mean, times N / (N - 1): the unbiased variance when every block
  // is taken once.
  auto variance = [&](int deviations) {
    if (pixels <= 0 || frames <= 0 || all_frames < 2) return 0.0;
    return linear(deviations) / (frames * pixels) * all_frames / (all_frames - 1);
  };
  Estimates e;
  e.tv_test = variance(kDT);
  e.tv_ref = variance(kDR);
  e.tv_err = variance(kDE);
  if (e.tv_ref > 0) e.tv_ratio = e.tv_test / e.tv_ref;
  const double sum_test = linear(kST) + frames * row[kT0], sum_ref = linear(kSR) + frames * row[kR0];
  if (sum_ref != 0) e.energy_bias = (sum_test - sum_ref) / sum_ref;
  e.relmse = pixels > 0 && frames > 0 ? linear(kSQ) / (frames * pixels) : 0.0;
  e.relmse_temporal = pixels > 0 && frames > 0 ? linear(kDQ) / (frames * pixels) : 0.0;
  e.relmse_spatial = e.relmse - e.relmse_temporal;
  e.flicker_index = row[kFlickerSegments] > 0 ? row[kFlickerPower] / row[kFlickerSegments] : 0.0;
  return e;
}

TileBlockStatistics::Estimates TileBlockStatistics::Evaluate(const std::vector<int>& tile_counts,
                                                             const std::vector<int>& block_counts) const {
  std::vector<double> sum(stride_, 0.0);
  for (int t = 0; t < tiles(); ++t) {
    const double w = tile_counts.empty() ? 1.0 : tile_counts[t];
    if (w == 0) continue;
    const double* row = rows_.data() + static_cast<size_t>(t) * stride_;
    for (int i = 0; i < stride_; ++i) sum[i] += w * row[i];
  }
  return FromSums(sum.data(), block_counts);
}

TileBlockStatistics::Intervals TileBlockStatistics::Bootstrap(const Estimates& point,
                                                              const BootstrapSettings& settings) const {
  const int tile_count = tiles(), k_count = blocks(), replicates = settings.replicates;
  // Per replicate: the joint resample (tiles and blocks), and the same
  // draws of tiles alone and of blocks alone, for the variance correction.
  std::vector<Estimates> joint(replicates), tiles_only(replicates), blocks_only(replicates);
  std::vector<double> all(stride_, 0.0);
  for (int t = 0; t < tile_count; ++t)
    for (int i = 0; i < stride_; ++i) all[i] += rows_[static_cast<size_t>(t) * stride_ + i];
  // Replicates in parallel, and in batches: a 1080p frame has 32 400 tiles,
  // 10 MiB of rows that one replicate at a time would stream from memory a
  // thousand times. A batch reads each tile's row once for all of its
  // replicates, and adds the tiles to each replicate's sums in tile order as
  // the serial loop did, so every sum keeps its bits. Replicate r draws
  // tile_count + k_count numbers and SplitMix64's state only advances by its
  // constant: replicate r starts where the serial loop would have.
  constexpr int kBatch = 32;
  const std::uint64_t draws_per_replicate = static_cast<std::uint64_t>(tile_count) + k_count;
  const int batches = (replicates + kBatch - 1) / kBatch;
  cv::parallel_for_(cv::Range(0, batches), [&](const cv::Range& range) {
    std::vector<int> w(static_cast<size_t>(tile_count) * kBatch);  // [tile][replicate in batch]
    std::vector<int> c(static_cast<size_t>(k_count) * kBatch);     // [replicate in batch][block]
    std::vector<double> sums(static_cast<size_t>(stride_) * kBatch);
    for (int b = range.start; b < range.end; ++b) {
      const int first = b * kBatch, count = std::min(kBatch, replicates - first);
      std::fill(w.begin(), w.end(), 0);
      std::fill(c.begin(), c.end(), 0);
      for (int j = 0; j < count; ++j) {
        const std::uint64_t r = static_cast<std::uint64_t>(first + j);
        SplitMix64 random{settings.seed + r * draws_per_replicate * SplitMix64::kGamma};
        for (int i = 0; i < tile_count; ++i) ++w[static_cast<size_t>(random.Below(tile_count)) * kBatch + j];
        for (int k = 0; k < k_count; ++k) ++c[static_cast<size_t>(j) * k_count + random.Below(k_count)];
      }
      std::fill(sums.begin(), sums.end(), 0.0);
      for (int t = 0; t < tile_count; ++t) {
        const double* row = rows_.data() + static_cast<size_t>(t) * stride_;
        const int* wt = w.data() + static_cast<size_t>(t) * kBatch;
        for (int j = 0; j < count; ++j) {
          if (wt[j] == 0) continue;
          const double weight = wt[j];
          double* sum = sums.data() + static_cast<size_t>(j) * stride_;
          for (int i = 0; i < stride_; ++i) sum[i] += weight * row[i];
        }
      }
      for (int j = 0; j < count; ++j) {
        const std::vector<int> blocks(c.begin() + j * k_count, c.begin() + (j + 1) * k_count);
        const double* sum = sums.data() + static_cast<size_t>(j) * stride_;
        joint[first + j] = FromSums(sum, blocks);
        tiles_only[first + j] = FromSums(sum, {});
        blocks_only[first + j] = FromSums(all.data(), blocks);
      }
    }
  });

  using Get = std::function<std::optional<double>(const Estimates&)>;
  auto interval = [&](std::optional<double> value, const Get& get, bool frames_resampled) -> std::optional<Interval> {
    if (!value) return std::nullopt;
    auto collect = [&](const std::vector<Estimates>& from) {
      std::vector<double> x;
      for (const Estimates& e : from)
        if (auto v = get(e); v && std::isfinite(*v)) x.push_back(*v);
      return x;
    };
    std::vector<double> spread = collect(frames_resampled ? joint : tiles_only);
    if (spread.size() < 2) return Interval{*value, *value};
    double scale = 1;
    if (frames_resampled) {
      // Resampling tiles and blocks independently counts the tile x block
      // interaction three times (McCullagh 2000; Owen 2007): with V_J, V_T,
      // V_B the joint, tiles-only and blocks-only variances, the interaction
      // is V_J - V_T - V_B, and V_T + V_B - that is the variance of the
      // estimate under the two-way random-effects model.
      const double vj = Variance(spread), vt = Variance(collect(tiles_only)), vb = Variance(collect(blocks_only));
      const double corrected = std::max({2 * (vt + vb) - vj, vt, vb});
      scale = vj > 0 ? std::sqrt(corrected / vj) : 0.0;
    }
    std::sort(spread.begin(), spread.end());
    // The percentile shape, centred on the estimate: the bootstrap median's
    // offset from it is resampling bias (duplicated blocks shrink variances).
    const double median = Quantile(spread, 0.5);
    return Interval{*value - scale * (median - Quantile(spread, 0.025)),
                    *value + scale * (Quantile(spread, 0.975) - median)};
  };
  Intervals out;
  out.tv_err = interval(
      point.tv_err, [](const Estimates& e) { return std::optional(e.tv_err); }, true);
  out.tv_ratio = interval(
      point.tv_ratio, [](const Estimates& e) { return e.tv_ratio; }, true);
  out.energy_bias = interval(
      point.energy_bias, [](const Estimates& e) { return e.energy_bias; }, true);
  out.relmse = interval(
      point.relmse, [](const Estimates& e) { return std::optional(e.relmse); }, true);
  out.relmse_temporal = interval(
      point.relmse_temporal, [](const Estimates& e) { return std::optional(e.relmse_temporal); }, true);
  out.relmse_spatial = interval(
      point.relmse_spatial, [](const Estimates& e) { return std::optional(e.relmse_spatial); }, true);
  // The spectrum needs the frames in order: only tiles are resampled for it.
  out.flicker_index = interval(
      point.flicker_index, [](const Estimates& e) { return std::optional(e.flicker_index); }, false);
  return out;
}

}  // namespace shimmer::metrics
