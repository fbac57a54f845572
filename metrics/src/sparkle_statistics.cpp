#include "shimmer/metrics/sparkle_statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace shimmer::metrics {

SparkleTracker::SparkleTracker(int width, int height, double contrast, int tile)
    : width_(width),
      height_(height),
      contrast_(contrast),
      tile_(std::max(tile, 1)),
      tiles_x_((width + tile_ - 1) / tile_),
      tiles_y_((height + tile_ - 1) / tile_),
      tile_in_region_(static_cast<size_t>(tiles_x_) * tiles_y_, 0),
      luminance_(height, width, CV_32F, cv::Scalar(0)),
      region_(height, width, CV_8U, cv::Scalar(0)),
      motion_rows_(height, nullptr),
      previous_(static_cast<size_t>(width) * height, 0),
      current_(static_cast<size_t>(width) * height, 0),
      rows_(height) {}

void SparkleTracker::AddRow(int y, const float* luminance, const uint8_t* region, const cv::Vec2f* motion) {
  std::copy(luminance, luminance + width_, luminance_.ptr<float>(y));
  std::copy(region, region + width_, region_.ptr<uint8_t>(y));
  motion_rows_[y] = motion;
}

SparkleTracker::RowCounts SparkleTracker::TrackRow(int y, const uint8_t* sparkle, const cv::Vec2f* motion) {
  const int w = width_, h = height_, t = frame_;
  int32_t* age = current_.data() + static_cast<size_t>(y) * w;
  const int32_t* before = previous_.data();
  RowCounts counts;
  counts.per_tile.assign(static_cast<size_t>(3) * tiles_x_, 0);
  for (int x = 0; x < w; ++x) {
    if (!sparkle[x]) {
      age[x] = 0;
      continue;
    }
    int* tile = counts.per_tile.data() + 3 * (x / tile_);
    int32_t oldest = 0;  // the largest age among the sparkles of frame t-1 at the warped position
    if (t > 0) {
      // Float, as WarpPrevious builds its map.
      float px = static_cast<float>(x), py = static_cast<float>(y);
      if (motion) {
        px += motion[x][0];
        py += motion[x][1];
      }
      // A position whose bilinear footprint has a pixel in the frame (NaN fails too).
      if (px > -1.f && px < static_cast<float>(w) && py > -1.f && py < static_cast<float>(h)) {
        const float fx = std::floor(px), fy = std::floor(py);
        const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
        // The pixels with nonzero bilinear weight: 1, 2 or 4.
        const int x1 = px > fx ? x0 + 1 : x0, y1 = py > fy ? y0 + 1 : y0;
        for (int qy = std::max(y0, 0); qy <= std::min(y1, h - 1); ++qy) {
          const int32_t* row = before + static_cast<size_t>(qy) * w;
          for (int qx = std::max(x0, 0); qx <= std::min(x1, w - 1); ++qx) oldest = std::max(oldest, row[qx]);
        }
      }
    }
    const int32_t a = oldest + 1;
    age[x] = a;
    ++counts.sparkles;
    ++tile[0];
    // A track that reaches frame 0 has age t + 1 (and any other at most t):
    // its birth was not seen, so it is left out of the lifetime.
    if (a <= t) ++counts.tracked, ++tile[2];
    if (a == 1 && t > 0) ++counts.births, ++tile[1];
  }
  return counts;
}

void SparkleTracker::EndFrame() {
  // The pixels that count: in the region and finite (NaN and +Inf never sparkle).
  cv::Mat weight(height_, width_, CV_32F), weighted(height_, width_, CV_32F);
  double region_sum = 0, region_pixels = 0;
  for (int y = 0; y < height_; ++y) {
    const float* v = luminance_.ptr<float>(y);
    const uint8_t* in = region_.ptr<uint8_t>(y);
    float* w = weight.ptr<float>(y);
    float* wv = weighted.ptr<float>(y);
    for (int x = 0; x < width_; ++x) {
      const bool counts = in[x] && std::isfinite(v[x]);
      if (in[x]) tile_in_region_[static_cast<size_t>(y / tile_) * tiles_x_ + x / tile_] = 1;
      w[x] = counts ? 1.f : 0.f;
      wv[x] = counts ? v[x] : 0.f;
      region_sum += wv[x], region_pixels += w[x];
    }
  }
  // The neighbourhood's mean as a normalised convolution, so that pixels
  // outside the region or the frame do not darken it; the pixel's own share
  // (the kernel's centre weight) is taken out again.
  const int radius = static_cast<int>(std::ceil(3 * kSparkleNeighbourhoodSigma));
  const cv::Mat kernel = cv::getGaussianKernel(2 * radius + 1, kSparkleNeighbourhoodSigma, CV_32F);
  const float centre = kernel.at<float>(radius) * kernel.at<float>(radius);
  cv::Mat sum_weight, sum_weighted;
  cv::sepFilter2D(weight, sum_weight, CV_32F, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
  cv::sepFilter2D(weighted, sum_weighted, CV_32F, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
  const double floor = region_pixels > 0 ? kSparkleFloorShare * region_sum / region_pixels : 0.0;
  cv::Mat sparkle(height_, width_, CV_8U, cv::Scalar(0));
  for (int y = 0; y < height_; ++y) {
    const float* v = luminance_.ptr<float>(y);
    const float* w = weight.ptr<float>(y);
    const float* sw = sum_weight.ptr<float>(y);
    const float* swv = sum_weighted.ptr<float>(y);
    uint8_t* out = sparkle.ptr<uint8_t>(y);
    for (int x = 0; x < width_; ++x) {
      if (w[x] == 0) continue;
      const double others = static_cast<double>(sw[x]) - centre;
      const double mean = others > 1e-6 ? (static_cast<double>(swv[x]) - centre * v[x]) / others : 0.0;
      out[x] = v[x] > contrast_ * std::max(mean, floor) && v[x] > 0;
    }
  }
  cv::parallel_for_(cv::Range(0, height_), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) rows_[y] = TrackRow(y, sparkle.ptr<uint8_t>(y), motion_rows_[y]);
  });
  long long sparkles = 0;
  const size_t frame_tiles = static_cast<size_t>(tiles_x_) * tiles_y_, first = tile_sparkles_.size();
  for (std::vector<int>* v : {&tile_sparkles_, &tile_births_, &tile_tracked_}) v->resize(first + frame_tiles, 0);
  for (int y = 0; y < height_; ++y) {
    const RowCounts& r = rows_[y];
    sparkles += r.sparkles;
    births_ += r.births;
    tracked_ += r.tracked;
    const size_t row = first + static_cast<size_t>(y / tile_) * tiles_x_;
    for (int i = 0; i < tiles_x_; ++i) {
      tile_sparkles_[row + i] += r.per_tile[3 * i];
      tile_births_[row + i] += r.per_tile[3 * i + 1];
      tile_tracked_[row + i] += r.per_tile[3 * i + 2];
    }
  }
  counts_.push_back(sparkles);
  if (frame_ > 0) later_sparkles_ += sparkles;
  std::swap(previous_, current_);
  std::fill(motion_rows_.begin(), motion_rows_.end(), nullptr);
  ++frame_;
}

SparkleStatistics SparkleTracker::Statistics() const {
  SparkleStatistics s;
  s.counts = counts_;
  s.births = births_;
  s.tracked = tracked_;
  const double n = static_cast<double>(counts_.size());
  if (counts_.empty()) return s;
  double sum = 0;
  for (long long c : counts_) sum += static_cast<double>(c);
  s.mean_count = sum / n;
  double squares = 0;
  for (long long c : counts_) squares += (c - s.mean_count) * (c - s.mean_count);
  s.count_variance = squares / n;
  if (s.mean_count > 0) s.count_cv = std::sqrt(s.count_variance) / s.mean_count;
  if (births_ > 0) s.mean_lifetime = static_cast<double>(tracked_) / static_cast<double>(births_);
  if (later_sparkles_ > 0) s.birth_rate = static_cast<double>(births_) / static_cast<double>(later_sparkles_);
  // The tiles that held region pixels, frame by frame.
  const size_t frame_tiles = tile_in_region_.size();
  std::vector<size_t> kept;
  for (size_t i = 0; i < frame_tiles; ++i)
    if (tile_in_region_[i]) kept.push_back(i);
  s.tiles = static_cast<int>(kept.size());
  for (size_t t = 0; t < counts_.size(); ++t)
    for (size_t i : kept) {
      s.tile_sparkles.push_back(tile_sparkles_[t * frame_tiles + i]);
      s.tile_births.push_back(tile_births_[t * frame_tiles + i]);
      s.tile_tracked.push_back(tile_tracked_[t * frame_tiles + i]);
    }
  return s;
}

void SetSparkleRatios(SparkleReport* report) {
  report->mean_count_ratio.reset();
  report->count_variance_ratio.reset();
  report->lifetime_ratio.reset();
  if (!report->reference) return;
  const SparkleStatistics &t = report->test, &r = *report->reference;
  if (r.mean_count > 0) report->mean_count_ratio = t.mean_count / r.mean_count;
  if (r.count_variance > 0) report->count_variance_ratio = t.count_variance / r.count_variance;
  if (t.mean_lifetime && r.mean_lifetime) report->lifetime_ratio = *t.mean_lifetime / *r.mean_lifetime;
}

namespace {

// The three ratios of one resample: tile i taken tile_counts[i] times and
// frame block k block_counts[k] times (null: each once). NaN where a ratio
// is undefined in that resample.
struct SparkleRatios {
  double count = std::numeric_limits<double>::quiet_NaN();
  double variance = std::numeric_limits<double>::quiet_NaN();
  double lifetime = std::numeric_limits<double>::quiet_NaN();
};

class SparkleResample {
 public:
  SparkleResample(const SparkleStatistics& test, const SparkleStatistics& reference, const std::vector<int>& block_frames)
      : test_(test), reference_(reference), frames_(static_cast<int>(test.counts.size())), tiles_(test.tiles) {
    for (int k = 0; k < static_cast<int>(block_frames.size()); ++k)
      for (int f = 0; f < block_frames[k]; ++f) block_of_.push_back(k);
  }

  SparkleRatios Evaluate(const int* tile_counts, const int* block_counts) const {
    // Per frame and side: sparkles, births, tracked over the resampled tiles.
    std::vector<double> sums(static_cast<size_t>(frames_) * 6, 0.0);
    for (int i = 0; i < tiles_; ++i) {
      const double w = tile_counts ? tile_counts[i] : 1;
      if (w == 0) continue;
      for (int t = 0; t < frames_; ++t) {
        const size_t at = static_cast<size_t>(t) * tiles_ + i;
        double* f = sums.data() + 6 * static_cast<size_t>(t);
        f[0] += w * test_.tile_sparkles[at];
        f[1] += w * test_.tile_births[at];
        f[2] += w * test_.tile_tracked[at];
        f[3] += w * reference_.tile_sparkles[at];
        f[4] += w * reference_.tile_births[at];
        f[5] += w * reference_.tile_tracked[at];
      }
    }
    // Over the resampled frames: count, count^2, births, tracked per side.
    double n = 0, a[8] = {};
    for (int t = 0; t < frames_; ++t) {
      const double c = block_counts ? block_counts[block_of_[t]] : 1;
      if (c == 0) continue;
      const double* f = sums.data() + 6 * static_cast<size_t>(t);
      n += c;
      for (int side = 0; side < 2; ++side) {
        a[4 * side] += c * f[3 * side];
        a[4 * side + 1] += c * f[3 * side] * f[3 * side];
        a[4 * side + 2] += c * f[3 * side + 1];
        a[4 * side + 3] += c * f[3 * side + 2];
      }
    }
    SparkleRatios r;
    if (n == 0) return r;
    const double mean_t = a[0] / n, mean_r = a[4] / n;
    const double var_t = std::max(a[1] / n - mean_t * mean_t, 0.0), var_r = std::max(a[5] / n - mean_r * mean_r, 0.0);
    if (mean_r > 0) r.count = mean_t / mean_r;
    if (var_r > 0) r.variance = var_t / var_r;
    if (a[2] > 0 && a[6] > 0 && a[7] > 0) r.lifetime = (a[3] / a[2]) / (a[7] / a[6]);
    return r;
  }

 private:
  const SparkleStatistics& test_;
  const SparkleStatistics& reference_;
  int frames_, tiles_;
  std::vector<int> block_of_;
};

}  // namespace

void SetSparkleIntervals(SparkleReport* report, const std::vector<int>& block_frames,
                         const BootstrapSettings& settings) {
  report->mean_count_ratio_ci.reset();
  report->count_variance_ratio_ci.reset();
  report->lifetime_ratio_ci.reset();
  if (!report->reference) return;
  const SparkleStatistics &test = report->test, &reference = *report->reference;
  const int frames = static_cast<int>(test.counts.size()), tiles = test.tiles;
  int blocked = 0;
  for (int f : block_frames) blocked += f;
  const size_t cells = static_cast<size_t>(frames) * tiles;
  if (frames < 2 || tiles == 0 || blocked != frames || reference.tiles != tiles ||
      reference.counts.size() != test.counts.size() || test.tile_sparkles.size() != cells ||
      reference.tile_sparkles.size() != cells)
    return;
  const SparkleResample resample(test, reference, block_frames);
  const int blocks = static_cast<int>(block_frames.size()), replicates = settings.replicates;
  // Per replicate: the joint resample, and its tiles alone and blocks alone.
  std::vector<SparkleRatios> joint(replicates), tiles_only(replicates), blocks_only(replicates);
  cv::parallel_for_(cv::Range(0, replicates), [&](const cv::Range& range) {
    std::vector<int> w(tiles), c(blocks);
    for (int r = range.start; r < range.end; ++r) {
      std::fill(w.begin(), w.end(), 0);
      std::fill(c.begin(), c.end(), 0);
      DrawReplicate(
          settings, r, tiles, blocks, [&](int i) { ++w[i]; }, [&](int k) { ++c[k]; });
      joint[r] = resample.Evaluate(w.data(), c.data());
      tiles_only[r] = resample.Evaluate(w.data(), nullptr);
      blocks_only[r] = resample.Evaluate(nullptr, c.data());
    }
  });
  auto interval = [&](const std::optional<double>& value, double SparkleRatios::*member) -> std::optional<Interval> {
    if (!value) return std::nullopt;
    auto finite = [&](const std::vector<SparkleRatios>& from) {
      std::vector<double> x;
      for (const SparkleRatios& s : from)
        if (std::isfinite(s.*member)) x.push_back(s.*member);
      return x;
    };
    const std::vector<double> tiles_spread = finite(tiles_only), blocks_spread = finite(blocks_only);
    Interval i = ScaledPercentile(*value, finite(joint), &tiles_spread, &blocks_spread);
    // The shape is centred on the ratio and may reach below 0, where no
    // ratio of counts, variances or lifetimes lies.
    i.lo = std::max(i.lo, 0.0);
    return i;
  };
  report->mean_count_ratio_ci = interval(report->mean_count_ratio, &SparkleRatios::count);
  report->count_variance_ratio_ci = interval(report->count_variance_ratio, &SparkleRatios::variance);
  report->lifetime_ratio_ci = interval(report->lifetime_ratio, &SparkleRatios::lifetime);
}

}  // namespace shimmer::metrics
