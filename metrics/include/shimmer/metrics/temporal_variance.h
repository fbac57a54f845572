// Per-pixel temporal mean and unbiased variance, streamed one frame at a time.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "shimmer/metrics/huge_page_allocator.h"

namespace shimmer::metrics {

// Running moments for every pixel of a W x H frame, in double.
// Welford's update (Welford 1962, Technometrics 4(3):419-420) avoids the
// cancellation of the textbook sum-of-squares formula, which loses every digit
// for a bright highlight (mean 1e3) flickering by 1e-3. Partial results from
// disjoint parts of the sequence combine with Chan, Golub & LeVeque's pairwise
// formula (Chan et al. 1979, "Updating formulae and a pairwise algorithm for
// computing sample variances", Stanford CS tech. report STAN-CS-79-773).
class TemporalMoments {
 public:
  TemporalMoments() = default;
  TemporalMoments(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }

  // One sample of pixel i (row-major index). Inline: the metrics pass calls it
  // for every pixel of every frame from many threads, each on its own rows.
  void Add(size_t i, double x) {
    const double n = ++count_[i];
    const double delta = x - mean_[i];
    mean_[i] += delta / n;
    m2_[i] += delta * (x - mean_[i]);
  }

  // The moments of pixels i, i+1, ... for code that updates a row of them at
  // once (pixel_row.h) with exactly Add's arithmetic.
  struct Span {
    std::uint32_t* count;
    double *mean, *m2;
  };
  Span At(size_t i) { return {count_.data() + i, mean_.data() + i, m2_.data() + i}; }

  // Folds in moments accumulated over other frames of the same pixels (Chan).
  void Merge(const TemporalMoments& other);

  std::uint32_t count(size_t i) const { return count_[i]; }
  double mean(size_t i) const { return mean_[i]; }
  // Unbiased: M2 / (n - 1); 0 for fewer than two samples.
  double variance(size_t i) const { return count_[i] > 1 ? m2_[i] / (count_[i] - 1.0) : 0.0; }

  cv::Mat MeanMap() const;      // CV_64F
  cv::Mat VarianceMap() const;  // CV_64F

 private:
  int width_ = 0, height_ = 0;
  HugePageVector<std::uint32_t> count_;
  HugePageVector<double> mean_, m2_;
};

}  // namespace shimmer::metrics
