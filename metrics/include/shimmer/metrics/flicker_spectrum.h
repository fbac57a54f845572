// The flicker spectrum: Welch's averaged periodogram of every pixel's time
// series, averaged over pixels, computed while the frames stream by.
//
// It equals, to float precision,
//   scipy.signal.welch(x, fs, window='hann', nperseg=L, noverlap=L//2,
//                      detrend='constant', scaling='density')   (one-sided)
// averaged over the region's pixels: a periodic Hann window of length L,
// segments starting every L - L//2 frames (a tail shorter than L is dropped, as
// scipy does), each segment's mean removed before windowing, |DFT|^2 scaled by
// 1 / (fs * sum(w^2)), and every bin except DC and (for even L) Nyquist doubled.
// Welch 1967, IEEE Trans. Audio Electroacoust. 15(2):70-73.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "shimmer/metrics/huge_page_allocator.h"

namespace shimmer::metrics {

// w[n] = 0.5 - 0.5 cos(2 pi n / L), n = 0..L-1 (scipy's get_window('hann', L)).
std::vector<double> PeriodicHann(int length);

// How many Welch segments N frames hold: (N - L) / (L - L/2) + 1, 0 if N < L.
int WelchSegmentCount(int frames, int segment_length);

// Frequencies of the one-sided bins: k fs / L, k = 0..L/2.
std::vector<double> WelchFrequencies(int segment_length, double fs);

// Streams frames in; keeps only the last L frames of the tracked pixels
// (a ring of L x P floats), never the whole sequence.
class FlickerSpectrum {
 public:
  // `pixels`: row-major indices of the tracked pixels in a frame.
  FlickerSpectrum(std::vector<int> pixels, int segment_length, double fs);

  // Frame t's signal (CV_32F, full frame). `excluded` (CV_8U, full frame,
  // nonzero = drop; may be empty) removes pixels from the segments that end at
  // or after this frame. Frames must come in order t = 0, 1, 2, ...
  void AddFrame(const cv::Mat& signal, const cv::Mat& excluded);

  int segment_length() const { return length_; }
  int segments() const { return segments_; }
  double fs() const { return fs_; }
  std::vector<double> Frequencies() const { return WelchFrequencies(length_, fs_); }
  // Mean over segments of the pixel-averaged one-sided density; zeros before
  // the first segment completes.
  std::vector<double> Psd() const;

  // Also keeps, per tracked pixel, sum_k weight_k psd_k over its segments
  // (its own one-sided densities, before the average over pixels) and how
  // many segments it entered: the per-tile flicker_index the bootstrap
  // resamples. Call before the first frame.
  void WeighPixels(std::vector<double> bin_weights);
  const std::vector<double>& pixel_weighted_power() const { return pixel_power_; }
  const std::vector<int>& pixel_segments() const { return pixel_segments_; }

 private:
  void AddSegment(int first_frame, const cv::Mat& excluded);

  std::vector<int> pixels_;
  int length_;
  int step_;
  double fs_;
  std::vector<double> window_;
  double density_scale_;        // 1 / (fs sum w^2)
  HugePageVector<float> ring_;  // slot (t mod L) holds frame t, P floats
  int frames_ = 0;
  int segments_ = 0;
  std::vector<double> psd_sum_;  // sum over segments of pixel-mean densities
  std::vector<double> bin_weights_, pixel_power_;
  std::vector<int> pixel_segments_;
};

// One series through the same code (tests, and users with a single probe).
std::vector<double> WelchPsd(const std::vector<double>& x, double fs, int segment_length);

struct BandPowers {
  double low = 0;   // [0, 2) Hz
  double mid = 0;   // [2, 8) Hz
  double high = 0;  // [8, fs/2] Hz
};
// Rectangle rule sum psd_k * fs / L over the bins inside each band: with it
// the bands add up to the PSD's integral, which Parseval ties to the
// window-weighted variance of the segments.
BandPowers IntegrateBands(const std::vector<double>& freq_hz, const std::vector<double>& psd);

}  // namespace shimmer::metrics
