// The per-pixel part of MetricsAccumulator::AddFrame for one row, four pixels
// at a time where the CPU has AVX2.
//
// Why a kernel of its own: the pixels of a row are independent except for
// the frame's sums (energy, squared and relative error), whose order decides
// their last bits. The kernel does everything that is independent per pixel
// (the three Welford updates, difference sums, the spectrum's signal) and
// leaves each pixel's terms of those sums in `terms`, for the caller to add
// up in pixel order as before. Every lane does exactly the double arithmetic
// of the scalar code (IEEE operations are correctly rounded whatever the
// vector width, and no fused multiply-add is used), so results stay bit for
// bit what they were.
#pragma once

#include <cstddef>
#include <cstdint>

#include "shimmer/metrics/block_bootstrap.h"
#include "shimmer/metrics/temporal_variance.h"

namespace shimmer::metrics::detail {

// relMSE's denominator offset (docs/metrics.md).
inline constexpr double kRelMseEpsilon = 0.01;

struct PixelRowInput {
  int width = 0;
  const float* test = nullptr;
  const float* reference = nullptr;      // null without a reference (then R = 0)
  const float* previous_test = nullptr;  // null at the first frame
  const float* previous_reference = nullptr;
  const uint8_t* region = nullptr;  // 1: measured
  bool signal_error = false;        // the spectrum's signal is E = T - R, else T
};

// Per pixel of the row, for the sums and bootstrap cells the caller adds up:
// zero where the pixel is outside the region or not finite.
struct PixelRowTerms {
  double *test, *reference, *error2, *relative2;  // T, R, E^2, E^2 / (R^2 + eps)
  uint8_t* updated;                               // 1: finite and never excluded; its moments took the frame
  long long samples = 0, non_finite = 0;
};

struct PixelRowState {
  uint8_t* excluded;  // sticky: a non-finite sample seen
  TemporalMoments::Span test, reference, error;
  double* diff_test;  // sum_t |T_t - T_{t-1}|
  double* diff_error;
  float* signal;
};

// Four pixels at a time where the CPU has AVX2, else UpdatePixelRowScalar.
void UpdatePixelRow(const PixelRowInput& in, PixelRowState& state, PixelRowTerms& terms);
// One pixel at a time: what every vector lane must reproduce bit for bit
// (tests/metrics/pixel_row_test.cpp holds the two against each other).
void UpdatePixelRowScalar(const PixelRowInput& in, PixelRowState& state, PixelRowTerms& terms);

// The bootstrap's and relMSE split's part of a row, with a reference (what
// MetricsAccumulator::AddCellRow adds): for each pixel UpdatePixelRow
// updated, its first moments into its cell of the frame's block, relMSE's
// joint sums and the reference noise's sums; per tile of the row, the sums
// that enter the tile linearly. The same contract as UpdatePixelRow: four
// pixels at a time where the CPU has AVX2, every lane the scalar code's double
// arithmetic, each tile's sums added in pixel order, so bit for bit the same.
struct CellRowInput {
  int width = 0;
  int tile = 0;  // the bootstrap's tile side
  const float* test = nullptr;
  const float* reference = nullptr;
  const float* reference_stderr = nullptr;  // null: no noise sums this frame
  const int* region_index = nullptr;        // the row's pixels' indices among the region's, -1 outside
  const uint8_t* updated = nullptr;         // PixelRowTerms::updated
  const double* relative2 = nullptr;        // PixelRowTerms::relative2
  bool first_frame = false;                 // the shifts (t0, r0) are this frame's values
};

struct CellRowState {
  float* shifts;  // (t0, r0) per region pixel
  float* cells;   // TileBlockStatistics::kPixelSums per region pixel, this frame's block
  double* joint;  // sum w, sum w E, sum w E^2 per region pixel
  double *noise, *weighted_noise, *relmse_noise;  // per region pixel; null without stderr
};

// Per tile of the row (ceil(width / tile) of them): its kSquareSums sums into
// tile_squares[tile * kSquareSums ...] and whether any pixel entered into
// tile_any[tile]; a tile with none has zeros.
void AddCellRow(const CellRowInput& in, CellRowState& state, double* tile_squares, uint8_t* tile_any);
void AddCellRowScalar(const CellRowInput& in, CellRowState& state, double* tile_squares, uint8_t* tile_any);

}  // namespace shimmer::metrics::detail
