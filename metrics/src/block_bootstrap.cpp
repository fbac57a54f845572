#include "shimmer/metrics/block_bootstrap.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>
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

// Resampling tiles and blocks independently counts the tile x block
// interaction three times (McCullagh 2000; Owen 2007): with V_J, V_T, V_B
// the joint, tiles-only and blocks-only variances, the interaction is
// V_J - V_T - V_B, and V_T + V_B - that is the variance of the estimate.
Interval ScaledPercentile(double value, std::vector<double> spread, const std::vector<double>* tiles,
                          const std::vector<double>* blocks) {
  if (spread.size() < 2) return Interval{value, value};
  double scale = 1;
  if (tiles && blocks) {
    const double vj = Variance(spread), vt = Variance(*tiles), vb = Variance(*blocks);
    const double corrected = std::max({2 * (vt + vb) - vj, vt, vb});
    scale = vj > 0 ? std::sqrt(corrected / vj) : 0.0;
  }
  std::sort(spread.begin(), spread.end());
  // The percentile shape, centred on the estimate: the bootstrap median's
  // offset from it is resampling bias (duplicated blocks shrink variances).
  const double median = Quantile(spread, 0.5);
  return Interval{value - scale * (median - Quantile(spread, 0.025)),
                  value + scale * (Quantile(spread, 0.975) - median)};
}

namespace {

std::uint64_t Mix(std::uint64_t hash, std::uint64_t value) {
  SplitMix64 mix{hash ^ value};
  return mix.Next();
}

constexpr char kDrawsMagic[] = "shimmer-draws-1";

}  // namespace

std::string EncodeDraws(const BootstrapDraws& draws) {
  const std::uint32_t n = static_cast<std::uint32_t>(draws.tv_err.joint.size());
  std::string out(kDrawsMagic, sizeof kDrawsMagic);
  auto put = [&](const void* data, size_t bytes) { out.append(static_cast<const char*>(data), bytes); };
  put(&draws.key, sizeof draws.key);
  put(&n, sizeof n);
  for (const Replicates* r : {&draws.tv_err, &draws.relmse})
    for (const std::vector<float>* v : {&r->joint, &r->tiles_only, &r->blocks_only}) {
      std::vector<float> padded(*v);
      padded.resize(n, std::nanf(""));
      put(padded.data(), n * sizeof(float));
    }
  return out;
}

std::optional<BootstrapDraws> DecodeDraws(std::string_view bytes) {
  const size_t head = sizeof kDrawsMagic + sizeof(std::uint64_t) + sizeof(std::uint32_t);
  if (bytes.size() < head || std::memcmp(bytes.data(), kDrawsMagic, sizeof kDrawsMagic) != 0) return std::nullopt;
  BootstrapDraws draws;
  std::uint32_t n = 0;
  std::memcpy(&draws.key, bytes.data() + sizeof kDrawsMagic, sizeof draws.key);
  std::memcpy(&n, bytes.data() + sizeof kDrawsMagic + sizeof draws.key, sizeof n);
  if (bytes.size() != head + 6 * size_t(n) * sizeof(float)) return std::nullopt;
  const char* at = bytes.data() + head;
  for (Replicates* r : {&draws.tv_err, &draws.relmse})
    for (std::vector<float>* v : {&r->joint, &r->tiles_only, &r->blocks_only}) {
      v->resize(n);
      std::memcpy(v->data(), at, n * sizeof(float));
      at += n * sizeof(float);
    }
  return draws;
}

Interval WidenedInQuadrature(double value, Interval interval, double sigma) {
  const double half = kZ95 * sigma;
  return Interval{value - std::hypot(value - interval.lo, half), value + std::hypot(interval.hi - value, half)};
}

std::optional<Interval> PairedDifference(double a, const Replicates& ra, double b, const Replicates& rb) {
  const size_t n = ra.joint.size();
  if (n < 2 || rb.joint.size() != n || ra.tiles_only.size() != n || rb.tiles_only.size() != n ||
      ra.blocks_only.size() != n || rb.blocks_only.size() != n)
    return std::nullopt;
  std::vector<double> joint, tiles, blocks;
  for (size_t i = 0; i < n; ++i) {
    const double j = double(ra.joint[i]) - rb.joint[i], t = double(ra.tiles_only[i]) - rb.tiles_only[i],
                 k = double(ra.blocks_only[i]) - rb.blocks_only[i];
    // A replicate is used whole or not at all, so the three stay paired.
    if (std::isfinite(j) && std::isfinite(t) && std::isfinite(k))
      joint.push_back(j), tiles.push_back(t), blocks.push_back(k);
  }
  if (joint.size() < 2) return std::nullopt;
  return ScaledPercentile(a - b, std::move(joint), &tiles, &blocks);
}

double PairedNoiseSigma(double ref_noise, double tv_test_a, double tv_test_b, int frames, long long pixels) {
  if (!(ref_noise > 0) || frames < 2 || pixels <= 0) return 0;
  const double spread = std::sqrt(std::max(tv_test_a, 0.0)) + std::sqrt(std::max(tv_test_b, 0.0));
  return 2 * std::sqrt(ref_noise * spread * spread / ((frames - 1) * double(pixels)));
}

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
  std::vector<float> means(static_cast<size_t>(kPixelSums) * k_count);
  std::vector<double> squares(static_cast<size_t>(kSquareSums) * k_count);
  const std::pair<CellSum, PixelSum> to_means[] = {
      {kSumT, kPixelT}, {kSumR, kPixelR}, {kWeight, kPixelWeight}, {kWeightedE, kPixelWeightedE}};
  const std::pair<CellSum, SquareSum> to_squares[] = {{kSquareT, kSquareSumT},
                                                      {kSquareR, kSquareSumR},
                                                      {kSquareE, kSquareSumE},
                                                      {kRelative, kSquareRelative},
                                                      {kWeightedE2, kSquareWeightedE2}};
  for (int k = 0; k < k_count; ++k) {
    for (auto [from, to] : to_means) means[to * k_count + k] = sums[from * k_count + k];
    for (auto [from, to] : to_squares) squares[to * k_count + k] = sums[from * k_count + k];
  }
  AddPixelMeans(tile, t0, r0, means.data(), flicker_power, flicker_segments);
  AddTileSquares(tile, squares.data());
}

// A block's squared deviations from the pixel's temporal mean m over the
// whole sequence, sum_t (x_t - m)^2 = S2 - 2 m S1 + n m^2, split: S2 enters
// through AddTileSquares, the rest, which needs the pixel's m, here.
void TileBlockStatistics::AddPixelMeans(int tile, double t0, double r0, const float* sums, double flicker_power,
                                        double flicker_segments) {
  const int k_count = blocks();
  auto in = [&](PixelSum kind, int k) { return double(sums[kind * k_count + k]); };
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
    frames += block_frames_[k], mean_t += in(kPixelT, k), mean_r += in(kPixelR, k);
    weight += in(kPixelWeight, k), weighted_e += in(kPixelWeightedE, k);
  }
  mean_t /= frames;
  mean_r /= frames;
  const double mean_e = mean_t - mean_r;
  const double mean_we = weight > 0 ? weighted_e / weight : 0.0;  // the relMSE-weighted mean of E - e0
  double* per_block = row + kScalars;
  for (int k = 0; k < k_count; ++k) {
    const double n = block_frames_[k], st = in(kPixelT, k), sr = in(kPixelR, k), se = st - sr;
    per_block[kST * k_count + k] += st;
    per_block[kSR * k_count + k] += sr;
    per_block[kDT * k_count + k] += n * mean_t * mean_t - 2 * mean_t * st;
    per_block[kDR * k_count + k] += n * mean_r * mean_r - 2 * mean_r * sr;
    per_block[kDE * k_count + k] += n * mean_e * mean_e - 2 * mean_e * se;
    per_block[kDQ * k_count + k] += mean_we * mean_we * in(kPixelWeight, k) - 2 * mean_we * in(kPixelWeightedE, k);
  }
}

void TileBlockStatistics::AddTileSquares(int tile, const double* sums) {
  const int k_count = blocks();
  double* per_block = rows_.data() + static_cast<size_t>(tile) * stride_ + kScalars;
  const std::pair<SquareSum, PerBlock> into[] = {
      {kSquareSumT, kDT}, {kSquareSumR, kDR}, {kSquareSumE, kDE}, {kSquareRelative, kSQ}, {kSquareWeightedE2, kDQ}};
  for (auto [from, to] : into)
    for (int k = 0; k < k_count; ++k) per_block[to * k_count + k] += sums[from * k_count + k];
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

namespace {

// sums[j] += w[t][j] * rows[t] over the tiles in order, for the `count`
// replicates of a batch (w is [tile][batch]). No branch on a zero draw: a
// third of the draws are zero, and mispredicting them cost more than adding
// their zeros (adding +-0 leaves every sum's bits as they were). Cloned for
// AVX2, without FMA: a fused multiply-add would round differently from the
// default clone.
__attribute__((target_clones("avx2", "default"))) void AddDrawnRows(const double* rows, int tile_count,
                                                                     int stride, const int* w, int batch,
                                                                     int count, double* sums) {
  for (int t = 0; t < tile_count; ++t) {
    const double* row = rows + static_cast<size_t>(t) * stride;
    const int* wt = w + static_cast<size_t>(t) * batch;
    for (int j = 0; j < count; ++j) {
      const double weight = wt[j];
      double* sum = sums + static_cast<size_t>(j) * stride;
      for (int i = 0; i < stride; ++i) sum[i] += weight * row[i];
    }
  }
}

}  // namespace

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
  // tile_count + k_count numbers (DrawReplicate).
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
      for (int j = 0; j < count; ++j)
        DrawReplicate(
            settings, first + j, tile_count, k_count, [&](int i) { ++w[static_cast<size_t>(i) * kBatch + j]; },
            [&](int k) { ++c[static_cast<size_t>(j) * k_count + k]; });
      std::fill(sums.begin(), sums.end(), 0.0);
      AddDrawnRows(rows_.data(), tile_count, stride_, w.data(), kBatch, count, sums.data());
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
  auto collect = [&](const std::vector<Estimates>& from, const Get& get) {
    std::vector<double> x;
    for (const Estimates& e : from)
      if (auto v = get(e); v && std::isfinite(*v)) x.push_back(*v);
    return x;
  };
  auto interval = [&](std::optional<double> value, const Get& get, bool frames_resampled) -> std::optional<Interval> {
    if (!value) return std::nullopt;
    if (!frames_resampled) return ScaledPercentile(*value, collect(tiles_only, get), nullptr, nullptr);
    const std::vector<double> tiles = collect(tiles_only, get), blocks = collect(blocks_only, get);
    return ScaledPercentile(*value, collect(joint, get), &tiles, &blocks);
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
  // The draws' key: what decides them (tile_count and k_count draws per
  // replicate from the seed) and the region they fell on.
  std::uint64_t key = Mix(Mix(settings.seed, static_cast<std::uint64_t>(replicates)), draws_per_replicate);
  for (int frames : block_frames_) key = Mix(key, static_cast<std::uint64_t>(frames));
  for (int t = 0; t < tile_count; ++t)
    key = Mix(key, static_cast<std::uint64_t>(rows_[static_cast<size_t>(t) * stride_ + kPixels]));
  out.draws.key = key;
  auto keep = [&](Replicates& r, auto member) {
    for (int i = 0; i < replicates; ++i) {
      r.joint.push_back(static_cast<float>(joint[i].*member));
      r.tiles_only.push_back(static_cast<float>(tiles_only[i].*member));
      r.blocks_only.push_back(static_cast<float>(blocks_only[i].*member));
    }
  };
  keep(out.draws.tv_err, &Estimates::tv_err);
  keep(out.draws.relmse, &Estimates::relmse);
  return out;
}

}  // namespace shimmer::metrics
