// 95 % intervals for the headline metrics from a block bootstrap over frames
// and pixel tiles, computed from per-(tile, frame-block) sufficient statistics
// so that the sequence is never held (docs/metrics.md, "Intervals").
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace shimmer::metrics {

struct BootstrapSettings {
  int replicates = 1000;
  int tile = 8;                   // square pixel tiles, tile x tile
  std::uint64_t seed = 20261201;  // fixed: reruns give identical intervals
};

// Frames per block: round(cbrt(N)), at least 2 and at most N (Kuensch 1989,
// Hall, Horowitz & Jing 1995: block length of order N^(1/3) for variances).
int FrameBlockLength(int frames);

struct Interval {
  double lo = 0, hi = 0;
};

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

// Replicate r's resample: `tiles` tiles, then `blocks` frame blocks, each
// drawn uniformly with replacement and handed to on_tile / on_block. Every
// bootstrap of one sequence draws replicate r alike, so that statistics
// resampled apart (TileBlockStatistics, the sparkle ratios) share their
// draws: replicate r starts where a serial loop over replicates would.
template <class OnTile, class OnBlock>
void DrawReplicate(const BootstrapSettings& settings, int r, int tiles, int blocks, OnTile on_tile, OnBlock on_block) {
  const std::uint64_t per_replicate = static_cast<std::uint64_t>(tiles) + static_cast<std::uint64_t>(blocks);
  SplitMix64 random{settings.seed + static_cast<std::uint64_t>(r) * per_replicate * SplitMix64::kGamma};
  for (int i = 0; i < tiles; ++i) on_tile(random.Below(tiles));
  for (int k = 0; k < blocks; ++k) on_block(random.Below(blocks));
}

// The interval rule of every bootstrap here, on replicates of a value: the
// percentile shape of `spread` (the joint replicates, or the tiles-only
// ones when frames were not resampled), centred on the value and, with
// `tiles` and `blocks`, scaled to the two-way random-effects variance.
Interval ScaledPercentile(double value, std::vector<double> spread, const std::vector<double>* tiles,
                          const std::vector<double>* blocks);

// The normal distribution's two-sided 95 % quantile.
inline constexpr double kZ95 = 1.959963984540054;

// `interval` about `value` with an independent normal error of standard
// deviation `sigma` added in quadrature: each side's half-width h becomes
// sqrt(h^2 + (kZ95 sigma)^2).
Interval WidenedInQuadrature(double value, Interval interval, double sigma);

// One metric's bootstrap replicates: the joint resample's, and the same
// draws' tiles alone and blocks alone (the variance correction's).
struct Replicates {
  std::vector<float> joint, tiles_only, blocks_only;
};

// What a bootstrap drew for the metrics a comparison ranks. Two rows with
// the same `key` were resampled with the same tiles and frame blocks in
// every replicate (same seed, replicate count, frame blocks and per-tile
// pixel counts of the region): their replicates pair, and a difference
// between them is measured without what the rows share, the reference's
// noise first (PairedDifference; docs/metrics.md, "Paired intervals").
struct BootstrapDraws {
  std::uint64_t key = 0;
  Replicates tv_err, relmse;
};
// A compact binary form for a results store (little-endian floats), and
// back; nullopt for bytes that are not one.
std::string EncodeDraws(const BootstrapDraws& draws);
std::optional<BootstrapDraws> DecodeDraws(std::string_view bytes);

// The 95 % interval of a - b, a and b one metric of two rows whose draws
// have the same key, by the interval rule of TileBlockStatistics::Bootstrap
// applied to the replicates' differences. nullopt when the replicates do
// not pair (different counts) or are too few.
std::optional<Interval> PairedDifference(double a, const Replicates& ra, double b, const Replicates& rb);

// The standard deviation that the reference's noise still adds to a paired
// tv_err difference of two test sequences T_a, T_b measured against one
// reference R + n: the noise cancels but for -2 cov_t(T_a - T_b, n) per
// pixel, whose variance is s^2 var_t(T_a - T_b) / (N - 1); averaged over
// `pixels` independent pixels, with F = mean s^2 and mean var_t(T_a - T_b)
// bounded by (sqrt(tv_test_a) + sqrt(tv_test_b))^2 (Minkowski).
double PairedNoiseSigma(double ref_noise, double tv_test_a, double tv_test_b, int frames, long long pixels);

// What the bootstrap resamples: one row of sums per tile, each over the
// tile's good region pixels, split by frame block. Values are shifted per
// pixel by its first frame (x - x_0) before summing, which leaves variances
// unchanged and keeps the float per-block sums free of cancellation.
class TileBlockStatistics {
 public:
  explicit TileBlockStatistics(std::vector<int> block_frames);

  int blocks() const { return static_cast<int>(block_frames_.size()); }
  int tiles() const { return static_cast<int>(rows_.size() / stride_); }

  // Starts a tile's row (all zeros); returns its index.
  int AddTile();
  // What a pixel brings per frame block, kind-major: sums[kind * blocks() + k].
  // Values are shifted by the pixel's first frame (t0, r0, e0 = t0 - r0);
  // w = 1 / (R^2 + eps) is the relMSE weight of each sample.
  enum CellSum {
    kSumT,        // sum (T - t0)
    kSumR,        // sum (R - r0)
    kSquareT,     // sum (T - t0)^2
    kSquareR,     // sum (R - r0)^2
    kSquareE,     // sum (E - e0)^2
    kRelative,    // sum w E^2
    kWeight,      // sum w
    kWeightedE,   // sum w (E - e0)
    kWeightedE2,  // sum w (E - e0)^2
    kCellSums
  };
  // One pixel: its first-frame values t0, r0, its per-block sums, and
  // `flicker_power` and `flicker_segments`: its Watson-weighted spectral
  // power summed over its segments, and their count. The same as
  // AddPixelMeans with its kSumT, kSumR, kWeight and kWeightedE and
  // AddTileSquares with the other five.
  void AddPixel(int tile, double t0, double r0, const float* sums, double flicker_power, double flicker_segments);

  // A pass need not keep all nine sums per pixel: only those that multiply
  // the pixel's own temporal mean (its first moments, PixelSum) are needed
  // per pixel; the rest enter a tile's row linearly and may be summed over
  // the tile as they come (SquareSum).
  enum PixelSum { kPixelT, kPixelR, kPixelWeight, kPixelWeightedE, kPixelSums };
  enum SquareSum { kSquareSumT, kSquareSumR, kSquareSumE, kSquareRelative, kSquareWeightedE2, kSquareSums };
  // One pixel's first moments per block, kind-major: sums[kind * blocks() + k].
  void AddPixelMeans(int tile, double t0, double r0, const float* sums, double flicker_power,
                     double flicker_segments);
  // A tile's linear sums over its pixels, kind-major: sums[kind * blocks() + k].
  void AddTileSquares(int tile, const double* sums);

  struct Estimates {
    double tv_test = 0, tv_ref = 0, tv_err = 0;
    std::optional<double> tv_ratio, energy_bias;
    double relmse = 0, flicker_index = 0;
    // relmse's split (docs/metrics.md, "Joint error"): the weighted variance
    // of E about each pixel's weighted temporal mean, and the rest.
    double relmse_temporal = 0, relmse_spatial = 0;
  };
  // The metrics of the data set made of tile i taken w[i] times and frame
  // block k taken c[k] times (empty w or c: each once).
  Estimates Evaluate(const std::vector<int>& tile_counts, const std::vector<int>& block_counts) const;

  struct Intervals {
    std::optional<Interval> tv_err, tv_ratio, energy_bias, relmse, relmse_temporal, relmse_spatial, flicker_index;
    BootstrapDraws draws;  // of tv_err and relmse, for paired comparisons
  };
  // The 95 % intervals about `point` (the metrics as computed by the pass).
  Intervals Bootstrap(const Estimates& point, const BootstrapSettings& settings) const;

 private:
  Estimates FromSums(const double* row, const std::vector<int>& block_counts) const;

  std::vector<int> block_frames_;
  int stride_ = 0;
  std::vector<double> rows_;
};

}  // namespace shimmer::metrics
