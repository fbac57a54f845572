#include "shimmer/metrics/sparkle_statistics.h"

#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace shimmer::metrics {

SparkleTracker::SparkleTracker(int width, int height, double contrast)
    : width_(width),
      height_(height),
      contrast_(contrast),
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
  for (int x = 0; x < w; ++x) {
    if (!sparkle[x]) {
      age[x] = 0;
      continue;
    }
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
    // A track that reaches frame 0 has age t + 1 (and any other at most t):
    // its birth was not seen, so it is left out of the lifetime.
    if (a <= t) ++counts.tracked;
    if (a == 1 && t > 0) ++counts.births;
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
  for (const RowCounts& r : rows_) {
    sparkles += r.sparkles;
    births_ += r.births;
    tracked_ += r.tracked;
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

}  // namespace shimmer::metrics
