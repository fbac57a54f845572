#include "shimmer/metrics/metrics_accumulator.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "pixel_row.h"
#include "shimmer/metrics/energy_bias.h"
#include "shimmer/metrics/temporal_sensitivity.h"

namespace shimmer::metrics {

namespace {

// relMSE's denominator offset: keeps near-black reference pixels from
// dominating (the convention of the rendering literature's relMSE, e.g.
// Rousselle et al. 2011, with 0.01 as docs/metrics.md defines it).
using detail::kRelMseEpsilon;

// Per (frame block, region pixel): a pixel's first moments
// (TileBlockStatistics::PixelSum); per (tile, frame block): the sums that
// enter a tile linearly (SquareSum).
constexpr int kPixelSums = TileBlockStatistics::kPixelSums;
constexpr int kSquareSums = TileBlockStatistics::kSquareSums;

// Per-row partial sums of one frame: rows are the unit of parallel work, so
// summing them in row order afterwards keeps results independent of threading.
struct RowSums {
  double test = 0, reference = 0, error2 = 0, relative2 = 0;
  long long samples = 0, non_finite = 0;
};

// In row order, as always: the sums' last bits depend on it.
RowSums SumOfRows(const std::vector<RowSums>& rows) {
  RowSums frame;
  for (const RowSums& r : rows) {
    frame.test += r.test;
    frame.reference += r.reference;
    frame.error2 += r.error2;
    frame.relative2 += r.relative2;
    frame.samples += r.samples;
    frame.non_finite += r.non_finite;
  }
  return frame;
}

double MeanOver(const cv::Mat& map, const cv::Mat& mask, long long count) {
  double sum = 0;
  for (int y = 0; y < map.rows; ++y) {
    const double* v = map.ptr<double>(y);
    const uint8_t* m = mask.ptr<uint8_t>(y);
    for (int x = 0; x < map.cols; ++x)
      if (m[x]) sum += v[x];
  }
  return count ? sum / count : 0.0;
}

cv::Mat MaskedFloat(const cv::Mat& map, const cv::Mat& mask) {
  cv::Mat out;
  map.convertTo(out, CV_32F);
  out.setTo(0, mask == 0);
  return out;
}

// cv::Mat::copyTo on one thread was a frame's last serial step.
void CopyOnEveryCore(const cv::Mat& from, cv::Mat& to) {
  to.create(from.size(), from.type());
  const size_t row_bytes = from.cols * from.elemSize();
  cv::parallel_for_(cv::Range(0, from.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) std::memcpy(to.ptr(y), from.ptr(y), row_bytes);
  });
}

std::vector<int> RegionIndices(const cv::Mat& region) {
  std::vector<int> indices;
  for (int y = 0; y < region.rows; ++y)
    for (int x = 0; x < region.cols; ++x)
      if (region.at<uint8_t>(y, x)) indices.push_back(y * region.cols + x);
  return indices;
}

}  // namespace

MetricsAccumulator::MetricsAccumulator(const AccumulatorSetup& setup)
    : setup_(setup),
      region_indices_(RegionIndices(setup.region)),
      region_pixels_(static_cast<long long>(region_indices_.size())),
      moments_test_(setup.width, setup.height),
      excluded_(cv::Mat::zeros(setup.height, setup.width, CV_8U)),
      diff_test_(cv::Mat::zeros(setup.height, setup.width, CV_64F)),
      signal_frame_(cv::Mat::zeros(setup.height, setup.width, CV_32F)),
      spectrum_(region_indices_, setup.segment_length, setup.fps) {
  if (setup.has_reference) {
    moments_ref_ = TemporalMoments(setup.width, setup.height);
    moments_err_ = TemporalMoments(setup.width, setup.height);
    diff_err_ = cv::Mat::zeros(setup.height, setup.width, CV_64F);
    region_index_.assign(static_cast<size_t>(setup.width) * setup.height, -1);
    for (size_t p = 0; p < region_indices_.size(); ++p) region_index_[region_indices_[p]] = static_cast<int>(p);
    block_length_ = FrameBlockLength(setup.frames);
    for (int t = 0; t < setup.frames; t += block_length_)
      block_frames_.push_back(std::min(block_length_, setup.frames - t));
    cells_.assign(block_frames_.size() * region_indices_.size() * kPixelSums, 0.f);
    const int tile = setup.bootstrap.tile;
    tiles_x_ = (setup.width + tile - 1) / tile;
    const int tiles_y = (setup.height + tile - 1) / tile;
    squares_.assign(static_cast<size_t>(tiles_x_) * tiles_y * kSquareSums * block_frames_.size(), 0.0);
    shifts_.assign(2 * region_indices_.size(), 0.f);
    joint_.assign(3 * region_indices_.size(), 0.0);
    if (setup.reference_stderr) {
      noise_.assign(region_indices_.size(), 0.0);
      relmse_noise_.assign(region_indices_.size(), 0.0);
      weighted_noise_.assign(region_indices_.size(), 0.0);
    }
    // The flicker weights of FlickerIndex, per bin, for the per-tile spectra.
    std::vector<double> freq = WelchFrequencies(setup.segment_length, setup.fps), weights;
    const double df = freq.size() > 1 ? freq[1] - freq[0] : 0.0;
    for (double f : freq) weights.push_back(WatsonTemporalGain(f) * WatsonTemporalGain(f) * df);
    spectrum_.WeighPixels(std::move(weights));
  }
  if (setup.sparkle_threshold > 0) {
    const int tile = setup.bootstrap.tile;
    sparkle_test_ = SparkleTracker(setup.width, setup.height, setup.sparkle_threshold, tile);
    if (setup.has_reference) sparkle_ref_ = SparkleTracker(setup.width, setup.height, setup.sparkle_threshold, tile);
  }
}

MetricsAccumulator::SparkleTracks MetricsAccumulator::TracksOf(const cv::Mat& motion, const cv::Mat& reference_motion) {
  // Each side follows its own motion vectors, else the other side's, else none.
  for (const cv::Mat* m : {&motion, &reference_motion})
    CV_Assert(m->empty() || (m->type() == CV_32FC2 && m->rows == setup_.height && m->cols == setup_.width));
  const cv::Mat* own_ref = setup_.has_reference && !reference_motion.empty() ? &reference_motion : nullptr;
  const cv::Mat* own_test = !motion.empty() ? &motion : nullptr;
  SparkleTracks tracks{own_test ? own_test : own_ref, own_ref ? own_ref : own_test};
  if (frames_added_ == 1) {
    auto whose = [&](const cv::Mat* m) { return !m ? "none" : m == &motion ? "test" : "reference"; };
    sparkle_motion_test_ = whose(tracks.test);
    sparkle_motion_ref_ = whose(tracks.reference);
  }
  return tracks;
}

// The bootstrap cells, relMSE's joint sums and the reference noise's sums of
// row y's updated pixels (with a reference): a pixel's first moments into
// `block_cells`, the sums that enter its tile linearly into that tile's
// row of `block` in squares_ (detail::AddCellRow, four pixels at a time).
void MetricsAccumulator::AddCellRow(int y, const float* tv_row, const float* rv_row, const float* se_row,
                                    const detail::PixelRowTerms& terms, float* block_cells, int block,
                                    std::vector<double>& tile_squares, std::vector<uint8_t>& tile_any) {
  const int tile = setup_.bootstrap.tile;
  const size_t blocks = block_frames_.size();
  const detail::CellRowInput in{.width = setup_.width,
                                .tile = tile,
                                .test = tv_row,
                                .reference = rv_row,
                                .reference_stderr = se_row,
                                .region_index = region_index_.data() + static_cast<size_t>(y) * setup_.width,
                                .updated = terms.updated,
                                .relative2 = terms.relative2,
                                .first_frame = frames_added_ == 0};
  const bool noise = se_row != nullptr;
  detail::CellRowState state{.shifts = shifts_.data(),
                             .cells = block_cells,
                             .joint = joint_.data(),
                             .noise = noise ? noise_.data() : nullptr,
                             .weighted_noise = noise ? weighted_noise_.data() : nullptr,
                             .relmse_noise = noise ? relmse_noise_.data() : nullptr};
  detail::AddCellRow(in, state, tile_squares.data(), tile_any.data());
  for (int tx = 0; tx < tiles_x_; ++tx) {
    if (!tile_any[tx]) continue;
    const size_t t = static_cast<size_t>(y / tile) * tiles_x_ + tx;
    double* tile_row = squares_.data() + t * kSquareSums * blocks;
    for (int kind = 0; kind < kSquareSums; ++kind) tile_row[kind * blocks + block] += tile_squares[tx * kSquareSums + kind];
  }
}

void MetricsAccumulator::AddFrame(const cv::Mat& T, const cv::Mat& Rf, const cv::Mat& motion,
                                  const std::string& test_source, const std::string& reference_source,
                                  const cv::Mat& reference_stderr, const cv::Mat& reference_motion) {
  const bool has_ref = setup_.has_reference;
  const bool sparkles = sparkle_test_.active();
  const SparkleTracks tracks = sparkles ? TracksOf(motion, reference_motion) : SparkleTracks{};
  const bool with_stderr = has_ref && setup_.reference_stderr && !reference_stderr.empty();
  if (with_stderr) ++stderr_frames_;
  const size_t region_count = region_indices_.size();
  const int block = has_ref ? std::min(frames_added_ / block_length_, static_cast<int>(block_frames_.size()) - 1) : 0;
  float* block_cells = has_ref ? cells_.data() + static_cast<size_t>(block) * region_count * kPixelSums : nullptr;
  const int width = setup_.width, height = setup_.height;
  const bool has_previous = frames_added_ > 0;
  std::vector<RowSums> rows(height);
  // In whole tile rows, so that one thread adds to a tile's squares_.
  const int tile = setup_.bootstrap.tile;
  cv::parallel_for_(cv::Range(0, (height + tile - 1) / tile), [&](const cv::Range& range) {
    std::vector<double> row_terms(4 * static_cast<size_t>(width));
    std::vector<uint8_t> updated(width);
    std::vector<double> tile_squares(has_ref ? static_cast<size_t>(tiles_x_) * kSquareSums : 0);
    std::vector<uint8_t> tile_any(has_ref ? tiles_x_ : 0);
    for (int y = range.start * tile; y < std::min(range.end * tile, height); ++y) {
      const size_t row = static_cast<size_t>(y) * width;
      const float* tv_row = T.ptr<float>(y);
      const float* rv_row = has_ref ? Rf.ptr<float>(y) : nullptr;
      const detail::PixelRowInput in{
          .width = width,
          .test = tv_row,
          .reference = rv_row,
          .previous_test = has_previous ? previous_test_.ptr<float>(y) : nullptr,
          .previous_reference = has_previous && has_ref ? previous_ref_.ptr<float>(y) : nullptr,
          .region = setup_.region.ptr<uint8_t>(y),
          .signal_error = setup_.signal == FlickerSignal::kError};
      detail::PixelRowState state{.excluded = excluded_.ptr<uint8_t>(y),
                                  .test = moments_test_.At(row),
                                  .reference = has_ref ? moments_ref_.At(row) : TemporalMoments::Span{},
                                  .error = has_ref ? moments_err_.At(row) : TemporalMoments::Span{},
                                  .diff_test = diff_test_.ptr<double>(y),
                                  .diff_error = has_ref ? diff_err_.ptr<double>(y) : nullptr,
                                  .signal = signal_frame_.ptr<float>(y)};
      detail::PixelRowTerms terms{.test = row_terms.data(),
                                  .reference = row_terms.data() + width,
                                  .error2 = row_terms.data() + 2 * width,
                                  .relative2 = row_terms.data() + 3 * width,
                                  .updated = updated.data()};
      detail::UpdatePixelRow(in, state, terms);
      RowSums sums;
      // In pixel order, as always: the sums' last bits depend on it.
      for (int x = 0; x < width; ++x) {
        sums.test += terms.test[x];
        sums.reference += terms.reference[x];
        sums.error2 += terms.error2[x];
        sums.relative2 += terms.relative2[x];
      }
      sums.samples = terms.samples;
      sums.non_finite = terms.non_finite;
      rows[y] = sums;
      if (sparkles) {
        sparkle_test_.AddRow(y, tv_row, in.region, tracks.test ? tracks.test->ptr<cv::Vec2f>(y) : nullptr);
        if (has_ref) sparkle_ref_.AddRow(y, rv_row, in.region, tracks.reference ? tracks.reference->ptr<cv::Vec2f>(y) : nullptr);
      }
      if (has_ref)
        AddCellRow(y, tv_row, rv_row, with_stderr ? reference_stderr.ptr<float>(y) : nullptr, terms, block_cells,
                   block, tile_squares, tile_any);
    }
  });

  const RowSums frame = SumOfRows(rows);
  if (frame.non_finite > 0) {
    nan_samples_ += frame.non_finite;
    if (first_non_finite_.empty()) first_non_finite_ = !has_ref || !cv::checkRange(T) ? test_source : reference_source;
  }
  if (has_ref && frame.samples > 0) {
    if (auto bias = RelativeBias(frame.test, frame.reference)) energy_bias_per_frame_.push_back(*bias);
    rmse_per_frame_.push_back(std::sqrt(frame.error2 / frame.samples));
    // relMSE is averaged the same way: per frame, then over frames.
    relmse_sum_ += frame.relative2 / frame.samples;
  }
  if (sparkles) {
    sparkle_test_.EndFrame();
    if (has_ref) sparkle_ref_.EndFrame();
  }
  spectrum_.AddFrame(signal_frame_, excluded_);
  if (setup_.with_motion && has_previous) warp_.AddFrame(previous_test_, T, motion, setup_.region, excluded_);
  // The planes may be reused by the caller: keep copies for the differences.
  CopyOnEveryCore(T, previous_test_);
  if (has_ref) CopyOnEveryCore(Rf, previous_ref_);
  ++frames_added_;
}

void MetricsAccumulator::AddIntervals(MetricsReport* report, const cv::Mat& good, double reference_sum) const {
  const int blocks = static_cast<int>(block_frames_.size());
  const size_t region_count = region_indices_.size();
  const int tile = setup_.bootstrap.tile;
  TileBlockStatistics cells(block_frames_);
  const std::vector<double>& flicker_power = spectrum_.pixel_weighted_power();
  const std::vector<int>& flicker_segments = spectrum_.pixel_segments();
  const int tiles_y = (setup_.height + tile - 1) / tile;
  // Only tiles that intersect the good region, each weighted by its pixels.
  // A tile with a pixel that turned non-finite after its first sample is
  // left out: that pixel's earlier samples are in the tile's squares_.
  // Which tiles enter is found on every core; their rows are then numbered
  // in tile order, as a serial loop would add them, and filled on every core
  // (each tile's row by one thread, its pixels in the serial loop's order).
  std::vector<int> row_of_tile(static_cast<size_t>(tiles_x_) * tiles_y, -1);
  cv::parallel_for_(cv::Range(0, tiles_y), [&](const cv::Range& rows) {
    for (int ty = rows.start * tile; ty < std::min(rows.end * tile, setup_.height); ty += tile)
      for (int tx = 0; tx < setup_.width; tx += tile) {
        bool tainted = false, any = false;
        for (int y = ty; y < std::min(ty + tile, setup_.height); ++y)
          for (int x = tx; x < std::min(tx + tile, setup_.width); ++x) {
            const size_t i = static_cast<size_t>(y) * setup_.width + x;
            if (setup_.region.at<uint8_t>(y, x) && !good.at<uint8_t>(y, x) && moments_test_.count(i) > 0)
              tainted = true;
            any = any || good.at<uint8_t>(y, x);
          }
        if (any && !tainted) row_of_tile[static_cast<size_t>(ty / tile) * tiles_x_ + tx / tile] = 0;
      }
  });
  for (int& row : row_of_tile)
    if (row == 0) row = cells.AddTile();
  std::vector<long long> row_used(static_cast<size_t>(tiles_y), 0);
  cv::parallel_for_(cv::Range(0, tiles_y), [&](const cv::Range& rows) {
    std::vector<float> sums(static_cast<size_t>(kPixelSums) * blocks);
    for (int row = rows.start; row < rows.end; ++row) {
      const int ty = row * tile;
      for (int tx = 0; tx < setup_.width; tx += tile) {
        const size_t t = static_cast<size_t>(row) * tiles_x_ + tx / tile;
        const int index = row_of_tile[t];
        if (index < 0) continue;
        for (int y = ty; y < std::min(ty + tile, setup_.height); ++y)
          for (int x = tx; x < std::min(tx + tile, setup_.width); ++x) {
            if (!good.at<uint8_t>(y, x)) continue;
            const int p = region_index_[static_cast<size_t>(y) * setup_.width + x];
            for (int k = 0; k < blocks; ++k)
              for (int s = 0; s < kPixelSums; ++s)
                sums[s * blocks + k] = cells_[(static_cast<size_t>(k) * region_count + p) * kPixelSums + s];
            cells.AddPixelMeans(index, shifts_[2 * p], shifts_[2 * p + 1], sums.data(), flicker_power[p],
                                flicker_segments[p]);
            ++row_used[row];
          }
        cells.AddTileSquares(index, squares_.data() + t * kSquareSums * blocks);
      }
    }
  });
  long long used = 0;
  for (long long n : row_used) used += n;
  // The reference noise's sums in the serial loop's order (tiles in order,
  // each tile's pixels in order), so that their last bits are as they were.
  double noise = 0, relmse_noise = 0, weighted_noise = 0;
  if (!noise_.empty())
    for (int ty = 0; ty < setup_.height; ty += tile)
      for (int tx = 0; tx < setup_.width; tx += tile) {
        if (row_of_tile[static_cast<size_t>(ty / tile) * tiles_x_ + tx / tile] < 0) continue;
        for (int y = ty; y < std::min(ty + tile, setup_.height); ++y)
          for (int x = tx; x < std::min(tx + tile, setup_.width); ++x) {
            if (!good.at<uint8_t>(y, x)) continue;
            const int p = region_index_[static_cast<size_t>(y) * setup_.width + x];
            noise += noise_[p];
            relmse_noise += relmse_noise_[p];
            weighted_noise += weighted_noise_[p];
          }
      }

  TileBlockStatistics::Estimates point;
  point.tv_err = report->tv_err.value_or(0);
  point.tv_ratio = report->tv_ratio;
  point.energy_bias = report->energy_bias;
  point.relmse = report->relmse.value_or(0);
  point.relmse_temporal = report->relmse_temporal.value_or(0);
  point.relmse_spatial = report->relmse_spatial.value_or(0);
  point.flicker_index = report->flicker.flicker_index;
  TileBlockStatistics::Intervals ci = cells.Bootstrap(point, setup_.bootstrap);
  if (!report->tv_err) ci.tv_err.reset();
  if (!report->relmse) ci.relmse.reset();
  if (!report->relmse_temporal) ci.relmse_temporal.reset(), ci.relmse_spatial.reset();
  report->bootstrap = MetricsReport::Bootstrap{setup_.bootstrap.replicates, block_length_, tile, setup_.bootstrap.seed};

  if (!noise_.empty() && stderr_frames_ == frames_added_ && used > 0) {
    const double frames = frames_added_;
    // Mean over M and t of stderr^2: what independent reference noise adds
    // to the temporal variance of E (and of R).
    const double floor = noise / (used * frames);
    const double tv_err = report->tv_err.value_or(0);
    report->tv_err_floor = tv_err > 0 ? std::min(floor / tv_err, 1.0) : (floor > 0 ? 1.0 : 0.0);
    report->ref_noise = floor;
    // Noise of a sum in quadrature with the bootstrap's half-widths.
    auto widen = [](std::optional<Interval>& interval, double value, double sigma) {
      if (interval) interval = WidenedInQuadrature(value, *interval, sigma);
    };
    if (ci.tv_err) ci.tv_err->lo = std::max(0.0, ci.tv_err->lo - floor);
    if (ci.tv_ratio && report->tv_ref && *report->tv_ref > floor)
      ci.tv_ratio->hi *= *report->tv_ref / (*report->tv_ref - floor);
    if (ci.energy_bias && reference_sum != 0)
      widen(ci.energy_bias, *report->energy_bias,
            std::abs((1 + *report->energy_bias) / reference_sum) * std::sqrt(noise));
    const double relmse_sigma = std::sqrt(relmse_noise) / (used * frames);
    if (report->relmse) report->relmse_noise_sigma = relmse_sigma;
    if (ci.relmse) widen(ci.relmse, *report->relmse, relmse_sigma);
    // The parts: the noise of their sum bounds each one's (to first order),
    // and independent reference noise adds mean(w s^2) to the temporal
    // part, as F adds to tv_err.
    if (ci.relmse_temporal) {
      widen(ci.relmse_temporal, *report->relmse_temporal, relmse_sigma);
      ci.relmse_temporal->lo = std::max(0.0, ci.relmse_temporal->lo - weighted_noise / (used * frames));
    }
    if (ci.relmse_spatial) widen(ci.relmse_spatial, *report->relmse_spatial, relmse_sigma);
    if (ci.flicker_index && setup_.signal == FlickerSignal::kError) {
      // White noise of variance `floor` in E: its Welch density is flat, 2 floor / fs one-sided.
      const FlickerResult& f = report->flicker;
      std::vector<double> white(f.freq_hz.size());
      for (size_t k = 0; k < white.size(); ++k) {
        const bool mirrored = k != 0 && !(f.segment_length % 2 == 0 && int(k) == f.segment_length / 2);
        white[k] = (mirrored ? 2.0 : 1.0) * floor / setup_.fps;
      }
      ci.flicker_index->lo = std::max(0.0, ci.flicker_index->lo - FlickerIndex(f.freq_hz, white));
    }
  }
  report->ci95 = ci;
}

Status MetricsAccumulator::Finish(MetricsReport* report) {
  const bool has_ref = setup_.has_reference;
  const int frames = frames_added_;
  // Pixels with any non-finite sample leave the region for every per-pixel
  // metric, so that all of them describe the same set of pixels.
  cv::Mat good = (setup_.region != 0) & (excluded_ == 0);
  good /= 255;
  const long long used = cv::countNonZero(good);
  report->nan_samples = nan_samples_;
  report->nan_pixels = region_pixels_ - used;
  if (used == 0)
    return Status::Failure("every pixel of the region has NaN or Inf values (first in " + first_non_finite_ + ")");
  if (report->nan_pixels > 0)
    report->warnings.push_back(std::to_string(report->nan_pixels) + " pixel(s) have NaN/Inf values (" +
                               std::to_string(nan_samples_) + " samples, first in " + first_non_finite_ +
                               "); excluded from the metrics");
  report->frames = frames;
  report->width = setup_.width;
  report->height = setup_.height;
  report->pixels = region_pixels_;
  report->region_mask = good;
  report->energy_bias_per_frame = energy_bias_per_frame_;
  report->rmse_per_frame = rmse_per_frame_;

  cv::Mat var_test = moments_test_.VarianceMap();
  report->tv_test = MeanOver(var_test, good, used);
  report->tv_test_map = MaskedFloat(var_test, good);
  report->temporal_diff_test = MeanOver(diff_test_, good, used) / (frames - 1);
  if (has_ref) {
    cv::Mat var_ref = moments_ref_.VarianceMap(), var_err = moments_err_.VarianceMap();
    report->tv_ref = MeanOver(var_ref, good, used);
    report->tv_err = MeanOver(var_err, good, used);
    report->tv_ref_map = MaskedFloat(var_ref, good);
    report->tv_err_map = MaskedFloat(var_err, good);
    if (*report->tv_ref > 0) report->tv_ratio = report->tv_test / *report->tv_ref;
    cv::Mat mean_test = moments_test_.MeanMap(), mean_ref = moments_ref_.MeanMap();
    // Every good pixel has all N samples, so sum_t = N * mean_t.
    report->energy_bias = RelativeBias(MeanOver(mean_test, good, 1) * frames, MeanOver(mean_ref, good, 1) * frames);
    report->energy_bias_map = EnergyBiasMap(mean_test, mean_ref, good, cv::Mat());
    report->ref_mean = MeanOver(mean_ref, good, used);
    report->temporal_diff_err = MeanOver(diff_err_, good, used) / (frames - 1);
    if (!rmse_per_frame_.empty()) {
      double rmse = 0;
      for (double r : rmse_per_frame_) rmse += r;
      report->rmse = rmse / rmse_per_frame_.size();
      report->relmse = relmse_sum_ / rmse_per_frame_.size();
      // The split over the good pixels, each pixel's mean error weighted as
      // its samples are: sum_t w (E - m)^2 + m^2 sum_t w = sum_t w E^2 with
      // m = sum_t w E / sum_t w, so the parts add up to relmse exactly (when
      // no sample was non-finite; else to relmse over the good pixels).
      double temporal = 0, spatial = 0;
      for (size_t p = 0; p < region_indices_.size(); ++p) {
        const int i = region_indices_[p];
        if (!good.at<uint8_t>(i / setup_.width, i % setup_.width)) continue;
        const double* joint = joint_.data() + 3 * p;
        if (!(joint[0] > 0)) continue;
        const double mean_part = joint[1] * joint[1] / joint[0];
        spatial += mean_part;
        temporal += std::max(0.0, joint[2] - mean_part);
      }
      report->relmse_temporal = temporal / (double(used) * frames);
      report->relmse_spatial = spatial / (double(used) * frames);
    }
    if (!report->tv_ratio)
      report->warnings.push_back("tv_ratio is undefined: the reference has zero temporal variance");
    if (!report->energy_bias) report->warnings.push_back("energy_bias is undefined: the reference sums to zero");
  }
  if (setup_.with_motion && !warp_.empty()) report->warp_err = warp_.mean();
  if (sparkle_test_.active()) {
    SparkleReport sparkles;
    sparkles.threshold = setup_.sparkle_threshold;
    sparkles.test = sparkle_test_.Statistics();
    sparkles.test.motion = sparkle_motion_test_;
    if (has_ref) {
      sparkles.reference = sparkle_ref_.Statistics();
      sparkles.reference->motion = sparkle_motion_ref_;
    }
    SetSparkleRatios(&sparkles);
    if (has_ref) SetSparkleIntervals(&sparkles, block_frames_, setup_.bootstrap);
    if (frames > 1 && sparkle_motion_test_ == "none")
      report->warnings.push_back(std::string("sparkle lifetimes tracked without motion vectors (") +
                                 (has_ref ? "neither TEST nor REF has" : "TEST has no") +
                                 " motion.X/Y): a sparkle that moves is a new birth in every frame it moves");
    report->sparkles = std::move(sparkles);
  }

  FlickerResult& f = report->flicker;
  f.signal = setup_.signal == FlickerSignal::kError ? "error" : "test";
  f.segment_length = setup_.segment_length;
  f.segments = spectrum_.segments();
  f.freq_hz = spectrum_.Frequencies();
  f.psd = spectrum_.Psd();
  BandPowers bands = IntegrateBands(f.freq_hz, f.psd);
  f.band_low = bands.low;
  f.band_mid = bands.mid;
  f.band_high = bands.high;
  f.flicker_index = FlickerIndex(f.freq_hz, f.psd);
  if (has_ref) AddIntervals(report, good, MeanOver(moments_ref_.MeanMap(), good, 1) * frames);
  return Ok();
}

}  // namespace shimmer::metrics
