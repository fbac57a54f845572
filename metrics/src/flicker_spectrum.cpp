#include "shimmer/metrics/flicker_spectrum.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace shimmer::metrics {

std::vector<double> PeriodicHann(int length) {
  std::vector<double> w(length);
  for (int n = 0; n < length; ++n) w[n] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * n / length);
  return w;
}

int WelchSegmentCount(int frames, int segment_length) {
  if (segment_length < 1 || frames < segment_length) return 0;
  const int step = segment_length - segment_length / 2;
  return (frames - segment_length) / step + 1;
}

std::vector<double> WelchFrequencies(int segment_length, double fs) {
  std::vector<double> f(segment_length / 2 + 1);
  for (size_t k = 0; k < f.size(); ++k) f[k] = static_cast<double>(k) * fs / segment_length;
  return f;
}

FlickerSpectrum::FlickerSpectrum(std::vector<int> pixels, int segment_length, double fs)
    : pixels_(std::move(pixels)),
      length_(segment_length),
      step_(segment_length - segment_length / 2),
      fs_(fs),
      window_(PeriodicHann(segment_length)),
      ring_(static_cast<size_t>(segment_length) * pixels_.size()),
      psd_sum_(segment_length / 2 + 1, 0.0) {
  if (segment_length < 2) throw std::invalid_argument("FlickerSpectrum: segment length must be >= 2");
  double sum_w2 = 0;
  for (double w : window_) sum_w2 += w * w;
  density_scale_ = 1.0 / (fs_ * sum_w2);
}

void FlickerSpectrum::WeighPixels(std::vector<double> bin_weights) {
  bin_weights_ = std::move(bin_weights);
  pixel_power_.assign(pixels_.size(), 0.0);
  pixel_segments_.assign(pixels_.size(), 0);
}

void FlickerSpectrum::AddFrame(const cv::Mat& signal, const cv::Mat& excluded) {
  CV_Assert(signal.type() == CV_32F && signal.isContinuous());
  float* slot = ring_.data() + static_cast<size_t>(frames_ % length_) * pixels_.size();
  const float* src = signal.ptr<float>();
  const int* idx = pixels_.data();
  const int count = static_cast<int>(pixels_.size());
  // A gather over every region pixel: on every core, in chunks.
  constexpr int kChunk = 1 << 16;
  cv::parallel_for_(cv::Range(0, (count + kChunk - 1) / kChunk), [&](const cv::Range& chunks) {
    for (int p = chunks.start * kChunk; p < std::min(chunks.end * kChunk, count); ++p) slot[p] = src[idx[p]];
  });
  ++frames_;
  const int first = frames_ - length_;
  if (first >= 0 && first % step_ == 0) AddSegment(first, excluded);
}

void FlickerSpectrum::AddSegment(int first_frame, const cv::Mat& excluded) {
  const int bins = length_ / 2 + 1;
  const int count = static_cast<int>(pixels_.size());
  // Blocks of pixels go through one row-wise cv::dft each: enough rows to
  // amortize the call, few enough to stay in cache.
  constexpr int kBlock = 256;
  const int blocks = (count + kBlock - 1) / kBlock;
  std::vector<double> block_sums(static_cast<size_t>(blocks) * bins, 0.0);
  std::vector<long> block_counts(blocks, 0);
  const uint8_t* drop = excluded.empty() ? nullptr : excluded.ptr<uint8_t>();

  cv::parallel_for_(cv::Range(0, blocks), [&](const cv::Range& range) {
    cv::Mat segment(kBlock, length_, CV_64F), spectrum;
    for (int b = range.start; b < range.end; ++b) {
      const int p0 = b * kBlock, rows = std::min(kBlock, count - p0);
      cv::Mat seg = segment.rowRange(0, rows);
      for (int j = 0; j < length_; ++j) {
        const float* slot = ring_.data() + static_cast<size_t>((first_frame + j) % length_) * pixels_.size() + p0;
        for (int r = 0; r < rows; ++r) seg.at<double>(r, j) = slot[r];
      }
      for (int r = 0; r < rows; ++r) {
        double* x = seg.ptr<double>(r);
        double mean = 0;  // detrend='constant'
        for (int j = 0; j < length_; ++j) mean += x[j];
        mean /= length_;
        for (int j = 0; j < length_; ++j) x[j] = (x[j] - mean) * window_[j];
      }
      cv::dft(seg, spectrum, cv::DFT_ROWS | cv::DFT_COMPLEX_OUTPUT);
      double* sums = block_sums.data() + static_cast<size_t>(b) * bins;
      long used = 0;
      for (int r = 0; r < rows; ++r) {
        if (drop && drop[pixels_[p0 + r]]) continue;
        const cv::Vec2d* X = spectrum.ptr<cv::Vec2d>(r);
        for (int k = 0; k < bins; ++k) sums[k] += X[k][0] * X[k][0] + X[k][1] * X[k][1];
        ++used;
        if (!bin_weights_.empty()) {
          double power = 0;
          for (int k = 0; k < bins; ++k) {
            const bool mirrored = k != 0 && !(length_ % 2 == 0 && k == length_ / 2);
            power += bin_weights_[k] * (mirrored ? 2.0 : 1.0) * (X[k][0] * X[k][0] + X[k][1] * X[k][1]);
          }
          pixel_power_[p0 + r] += power * density_scale_;
          ++pixel_segments_[p0 + r];
        }
      }
      block_counts[b] = used;
    }
  });

  std::vector<double> total(bins, 0.0);
  long used = 0;
  for (int b = 0; b < blocks; ++b) {
    used += block_counts[b];
    for (int k = 0; k < bins; ++k) total[k] += block_sums[static_cast<size_t>(b) * bins + k];
  }
  if (used == 0) return;
  for (int k = 0; k < bins; ++k) {
    // One-sided: fold negative frequencies onto positive ones, except the
    // bins that have no mirror (DC, and Nyquist when L is even).
    const bool mirrored = k != 0 && !(length_ % 2 == 0 && k == length_ / 2);
    psd_sum_[k] += total[k] / used * density_scale_ * (mirrored ? 2.0 : 1.0);
  }
  ++segments_;
}

std::vector<double> FlickerSpectrum::Psd() const {
  std::vector<double> psd(psd_sum_.size(), 0.0);
  if (segments_ == 0) return psd;
  for (size_t k = 0; k < psd.size(); ++k) psd[k] = psd_sum_[k] / segments_;
  return psd;
}

std::vector<double> WelchPsd(const std::vector<double>& x, double fs, int segment_length) {
  FlickerSpectrum spectrum({0}, segment_length, fs);
  cv::Mat frame(1, 1, CV_32F);
  for (double v : x) {
    frame.at<float>(0, 0) = static_cast<float>(v);
    spectrum.AddFrame(frame, cv::Mat());
  }
  return spectrum.Psd();
}

BandPowers IntegrateBands(const std::vector<double>& freq_hz, const std::vector<double>& psd) {
  BandPowers bands;
  if (freq_hz.size() < 2) return bands;
  const double df = freq_hz[1] - freq_hz[0];
  for (size_t k = 0; k < psd.size(); ++k) {
    const double power = psd[k] * df;
    if (freq_hz[k] < 2.0)
      bands.low += power;
    else if (freq_hz[k] < 8.0)
      bands.mid += power;
    else
      bands.high += power;
  }
  return bands;
}

}  // namespace shimmer::metrics
