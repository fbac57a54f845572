#include "shimmer/metrics/sparkle_statistics.h"

#include <algorithm>
#include <cmath>

namespace shimmer::metrics {

SparkleTracker::SparkleTracker(int width, int height, double threshold)
    : width_(width),
      height_(height),
      threshold_(threshold),
      previous_(static_cast<size_t>(width) * height, 0),
      current_(static_cast<size_t>(width) * height, 0),
      rows_(height) {}

void SparkleTracker::AddRow(int y, const float* luminance, const uint8_t* region, const cv::Vec2f* motion) {
  const int w = width_, h = height_, t = frame_;
  int32_t* age = current_.data() + static_cast<size_t>(y) * w;
  const int32_t* before = previous_.data();
  RowCounts counts;
  for (int x = 0; x < w; ++x) {
    const double v = luminance[x];
    // A sparkle: in the region, above tau, and finite (NaN fails the first test, +Inf the second).
    if (!region[x] || !(v > threshold_) || std::isinf(v)) {
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
  rows_[y] = counts;
}

void SparkleTracker::EndFrame() {
  long long sparkles = 0;
  for (const RowCounts& r : rows_) {
    sparkles += r.sparkles;
    births_ += r.births;
    tracked_ += r.tracked;
  }
  counts_.push_back(sparkles);
  if (frame_ > 0) later_sparkles_ += sparkles;
  std::swap(previous_, current_);
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
