#include "pixel_row.h"

#include <immintrin.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace shimmer::metrics::detail {

namespace {

// Welford's update, as TemporalMoments::Add.
inline void Welford(const TemporalMoments::Span& m, int x, double v) {
  const double n = ++m.count[x];
  const double delta = v - m.mean[x];
  m.mean[x] += delta / n;
  m.m2[x] += delta * (v - m.mean[x]);
}

// One pixel, the reference for the vector lanes below (and the whole row on
// CPUs without AVX2).
inline void UpdatePixel(const PixelRowInput& in, PixelRowState& s, PixelRowTerms& t, int x) {
  t.test[x] = t.reference[x] = t.error2[x] = t.relative2[x] = 0;
  t.updated[x] = 0;
  if (!in.region[x]) return;
  const double tv = in.test[x], rv = in.reference ? in.reference[x] : 0.0;
  if (!std::isfinite(tv) || !std::isfinite(rv)) {
    // Excluded and counted, never propagated: one NaN would otherwise turn
    // every mean and the whole spectrum into NaN.
    ++t.non_finite;
    s.excluded[x] = 1;
    s.signal[x] = 0;
    return;
  }
  const double e = tv - rv;
  t.test[x] = tv;
  t.reference[x] = rv;
  t.error2[x] = e * e;
  t.relative2[x] = e * e / (rv * rv + kRelMseEpsilon);
  ++t.samples;
  if (s.excluded[x]) {
    s.signal[x] = 0;
    return;
  }
  t.updated[x] = 1;
  Welford(s.test, x, tv);
  if (in.reference) {
    Welford(s.reference, x, rv);
    Welford(s.error, x, e);
  }
  if (in.previous_test) {
    s.diff_test[x] += std::abs(tv - in.previous_test[x]);
    if (in.reference)
      s.diff_error[x] += std::abs(e - (static_cast<double>(in.previous_test[x]) - in.previous_reference[x]));
  }
  s.signal[x] = static_cast<float>(in.signal_error ? e : tv);
}

// Four bytes of 0/1 flags as 64-bit lane masks (all ones where set).
__attribute__((target("avx2"))) inline __m256d Mask4(const uint8_t* flags) {
  int32_t word;
  std::memcpy(&word, flags, 4);
  const __m256i wide = _mm256_cvtepu8_epi64(_mm_cvtsi32_si128(word));
  return _mm256_castsi256_pd(_mm256_cmpgt_epi64(wide, _mm256_setzero_si256()));
}

// The four 64-bit lane masks as 32-bit ones, for the float and count lanes.
__attribute__((target("avx2"))) inline __m128i Narrow(__m256d mask) {
  const __m256i picked =
      _mm256_permutevar8x32_epi32(_mm256_castpd_si256(mask), _mm256_setr_epi32(0, 2, 4, 6, 0, 0, 0, 0));
  return _mm256_castsi256_si128(picked);
}

__attribute__((target("avx2"))) inline void Welford4(const TemporalMoments::Span& m, int x, __m256d v, __m256d take,
                                                     __m128i take32) {
  __m128i count = _mm_loadu_si128(reinterpret_cast<const __m128i*>(m.count + x));
  count = _mm_sub_epi32(count, take32);  // mask lanes are -1: +1 where taken
  _mm_storeu_si128(reinterpret_cast<__m128i*>(m.count + x), count);
  // Counts stay far below 2^31, where the signed conversion is the unsigned one.
  const __m256d n = _mm256_cvtepi32_pd(count);
  const __m256d mean = _mm256_loadu_pd(m.mean + x), m2 = _mm256_loadu_pd(m.m2 + x);
  const __m256d delta = _mm256_sub_pd(v, mean);
  const __m256d mean_new = _mm256_add_pd(mean, _mm256_div_pd(delta, n));
  const __m256d m2_new = _mm256_add_pd(m2, _mm256_mul_pd(delta, _mm256_sub_pd(v, mean_new)));
  _mm256_storeu_pd(m.mean + x, _mm256_blendv_pd(mean, mean_new, take));
  _mm256_storeu_pd(m.m2 + x, _mm256_blendv_pd(m2, m2_new, take));
}

// Bits 0..3 of `bits` as bytes 0/1 at out[0..3], or-ed into what is there.
inline void OrFlags(uint8_t* out, int bits) {
  for (int j = 0; j < 4; ++j) out[j] |= static_cast<uint8_t>((bits >> j) & 1);
}

__attribute__((target("avx2"))) void UpdateRowAvx2(const PixelRowInput& in, PixelRowState& s, PixelRowTerms& t) {
  const __m256d infinity = _mm256_set1_pd(HUGE_VAL), sign = _mm256_set1_pd(-0.0), zero = _mm256_setzero_pd();
  const __m256d epsilon = _mm256_set1_pd(kRelMseEpsilon);
  const bool with_reference = in.reference != nullptr;
  int x = 0;
  for (; x + 4 <= in.width; x += 4) {
    const __m256d region = Mask4(in.region + x);
    const int region_bits = _mm256_movemask_pd(region);
    if (region_bits == 0) {
      std::memset(t.updated + x, 0, 4);
      for (double* terms : {t.test, t.reference, t.error2, t.relative2}) _mm256_storeu_pd(terms + x, zero);
      continue;
    }
    const __m256d tv = _mm256_cvtps_pd(_mm_loadu_ps(in.test + x));
    const __m256d rv = with_reference ? _mm256_cvtps_pd(_mm_loadu_ps(in.reference + x)) : zero;
    // |v| < inf is false for NaN (ordered compare) and for +-inf.
    const __m256d finite = _mm256_and_pd(_mm256_cmp_pd(_mm256_andnot_pd(sign, tv), infinity, _CMP_LT_OQ),
                                         _mm256_cmp_pd(_mm256_andnot_pd(sign, rv), infinity, _CMP_LT_OQ));
    const __m256d counted = _mm256_and_pd(region, finite);
    const __m256d take = _mm256_andnot_pd(Mask4(s.excluded + x), counted);
    const int counted_bits = _mm256_movemask_pd(counted), take_bits = _mm256_movemask_pd(take);
    const int non_finite_bits = region_bits & ~counted_bits;
    t.samples += std::popcount(static_cast<unsigned>(counted_bits));
    t.non_finite += std::popcount(static_cast<unsigned>(non_finite_bits));
    OrFlags(s.excluded + x, non_finite_bits);
    std::memset(t.updated + x, 0, 4);
    OrFlags(t.updated + x, take_bits);

    const __m256d e = _mm256_sub_pd(tv, rv);
    const __m256d e2 = _mm256_mul_pd(e, e);
    const __m256d relative = _mm256_div_pd(e2, _mm256_add_pd(_mm256_mul_pd(rv, rv), epsilon));
    // And-ing with the mask leaves +0 where a pixel does not count: adding
    // +0 to a sum that started at +0 changes none of its bits.
    _mm256_storeu_pd(t.test + x, _mm256_and_pd(tv, counted));
    _mm256_storeu_pd(t.reference + x, _mm256_and_pd(rv, counted));
    _mm256_storeu_pd(t.error2 + x, _mm256_and_pd(e2, counted));
    _mm256_storeu_pd(t.relative2 + x, _mm256_and_pd(relative, counted));

    // The spectrum's signal: the value where taken, 0 where in the region but
    // not taken, untouched outside.
    const __m128 value = _mm256_cvtpd_ps(in.signal_error ? e : tv);
    const __m128 old = _mm_loadu_ps(s.signal + x);
    const __m128 in_region = _mm_castsi128_ps(Narrow(region));
    const __m128i take32 = Narrow(take);
    _mm_storeu_ps(s.signal + x, _mm_blendv_ps(old, _mm_and_ps(value, _mm_castsi128_ps(take32)), in_region));
    if (take_bits == 0) continue;

    Welford4(s.test, x, tv, take, take32);
    if (with_reference) {
      Welford4(s.reference, x, rv, take, take32);
      Welford4(s.error, x, e, take, take32);
    }
    if (in.previous_test) {
      const __m256d tp = _mm256_cvtps_pd(_mm_loadu_ps(in.previous_test + x));
      const __m256d dt = _mm256_loadu_pd(s.diff_test + x);
      const __m256d dt_new = _mm256_add_pd(dt, _mm256_andnot_pd(sign, _mm256_sub_pd(tv, tp)));
      _mm256_storeu_pd(s.diff_test + x, _mm256_blendv_pd(dt, dt_new, take));
      if (with_reference) {
        const __m256d rp = _mm256_cvtps_pd(_mm_loadu_ps(in.previous_reference + x));
        const __m256d de = _mm256_loadu_pd(s.diff_error + x);
        const __m256d de_new = _mm256_add_pd(de, _mm256_andnot_pd(sign, _mm256_sub_pd(e, _mm256_sub_pd(tp, rp))));
        _mm256_storeu_pd(s.diff_error + x, _mm256_blendv_pd(de, de_new, take));
      }
    }
  }
  for (; x < in.width; ++x) UpdatePixel(in, s, t, x);
}

using S = TileBlockStatistics;

// One updated pixel of AddCellRow into its cell, joint and noise sums and its
// tile's `squares`: the reference for the vector lanes below.
inline void AddCellPixel(const CellRowInput& in, CellRowState& s, int x, double* squares) {
  const double tv = in.test[x], rv = in.reference[x];
  const double e = tv - rv;
  const size_t p = static_cast<size_t>(in.region_index[x]);
  if (in.first_frame) {
    s.shifts[2 * p] = static_cast<float>(tv);
    s.shifts[2 * p + 1] = static_cast<float>(rv);
  }
  const double dt = tv - s.shifts[2 * p], dr = rv - s.shifts[2 * p + 1], de = dt - dr;
  const double denominator = rv * rv + kRelMseEpsilon;
  const double w = 1 / denominator;
  float* cell = s.cells + p * S::kPixelSums;
  cell[S::kPixelT] += static_cast<float>(dt);
  cell[S::kPixelR] += static_cast<float>(dr);
  cell[S::kPixelWeight] += static_cast<float>(w);
  cell[S::kPixelWeightedE] += static_cast<float>(w * de);
  squares[S::kSquareSumT] += dt * dt;
  squares[S::kSquareSumR] += dr * dr;
  squares[S::kSquareSumE] += de * de;
  squares[S::kSquareRelative] += in.relative2[x];  // e^2 / denominator
  squares[S::kSquareWeightedE2] += w * de * de;
  double* joint = s.joint + 3 * p;
  joint[0] += w, joint[1] += w * e, joint[2] += w * e * e;
  if (in.reference_stderr && std::isfinite(in.reference_stderr[x])) {
    const double s2 = double(in.reference_stderr[x]) * in.reference_stderr[x];
    s.noise[p] += s2;
    s.weighted_noise[p] += w * s2;
    // d/dR of E^2 / (R^2 + eps), with E = T - R (the delta method).
    const double slope = -2 * e / denominator - 2 * rv * e * e / (denominator * denominator);
    s.relmse_noise[p] += slope * slope * s2;
  }
}

// at[0..3] += term in the lanes `where` is set.
__attribute__((target("avx2"))) inline void AddWhere(double* at, __m256d term, __m256d where) {
  const __m256d old = _mm256_loadu_pd(at);
  _mm256_storeu_pd(at, _mm256_blendv_pd(old, _mm256_add_pd(old, term), where));
}

// Four updated pixels x..x+3: all in the region, so their region indices
// are consecutive and their cells, joint and noise sums lie side by side.
__attribute__((target("avx2"))) inline void AddCellPixels4(const CellRowInput& in, CellRowState& s, int x,
                                                           double* squares) {
  static_assert(S::kPixelT == 0 && S::kPixelR == 1 && S::kPixelWeight == 2 && S::kPixelWeightedE == 3 &&
                S::kPixelSums == 4);
  const __m256d tv = _mm256_cvtps_pd(_mm_loadu_ps(in.test + x)), rv = _mm256_cvtps_pd(_mm_loadu_ps(in.reference + x));
  const __m256d e = _mm256_sub_pd(tv, rv);
  const size_t p = static_cast<size_t>(in.region_index[x]);
  float* shifts = s.shifts + 2 * p;
  if (in.first_frame) {
    const __m128 t32 = _mm256_cvtpd_ps(tv), r32 = _mm256_cvtpd_ps(rv);
    _mm_storeu_ps(shifts, _mm_unpacklo_ps(t32, r32));
    _mm_storeu_ps(shifts + 4, _mm_unpackhi_ps(t32, r32));
  }
  const __m128 pairs_lo = _mm_loadu_ps(shifts), pairs_hi = _mm_loadu_ps(shifts + 4);
  const __m256d t0 = _mm256_cvtps_pd(_mm_shuffle_ps(pairs_lo, pairs_hi, _MM_SHUFFLE(2, 0, 2, 0)));
  const __m256d r0 = _mm256_cvtps_pd(_mm_shuffle_ps(pairs_lo, pairs_hi, _MM_SHUFFLE(3, 1, 3, 1)));
  const __m256d dt = _mm256_sub_pd(tv, t0), dr = _mm256_sub_pd(rv, r0), de = _mm256_sub_pd(dt, dr);
  const __m256d denominator = _mm256_add_pd(_mm256_mul_pd(rv, rv), _mm256_set1_pd(kRelMseEpsilon));
  const __m256d w = _mm256_div_pd(_mm256_set1_pd(1.0), denominator);
  const __m256d w_de = _mm256_mul_pd(w, de);

  // The four cells, pixel-major: transpose the four sums' lanes.
  __m128 cell_t = _mm256_cvtpd_ps(dt), cell_r = _mm256_cvtpd_ps(dr), cell_w = _mm256_cvtpd_ps(w),
         cell_we = _mm256_cvtpd_ps(w_de);
  _MM_TRANSPOSE4_PS(cell_t, cell_r, cell_w, cell_we);
  float* cells = s.cells + p * S::kPixelSums;
  _mm_storeu_ps(cells, _mm_add_ps(_mm_loadu_ps(cells), cell_t));
  _mm_storeu_ps(cells + 4, _mm_add_ps(_mm_loadu_ps(cells + 4), cell_r));
  _mm_storeu_ps(cells + 8, _mm_add_ps(_mm_loadu_ps(cells + 8), cell_w));
  _mm_storeu_ps(cells + 12, _mm_add_ps(_mm_loadu_ps(cells + 12), cell_we));

  // The tile's sums and the joint sums, one lane after the other (pixel order).
  alignas(32) double lanes[8][4];
  _mm256_store_pd(lanes[0], _mm256_mul_pd(dt, dt));
  _mm256_store_pd(lanes[1], _mm256_mul_pd(dr, dr));
  _mm256_store_pd(lanes[2], _mm256_mul_pd(de, de));
  _mm256_store_pd(lanes[3], _mm256_loadu_pd(in.relative2 + x));
  _mm256_store_pd(lanes[4], _mm256_mul_pd(w_de, de));
  const __m256d w_e = _mm256_mul_pd(w, e);
  _mm256_store_pd(lanes[5], w);
  _mm256_store_pd(lanes[6], w_e);
  _mm256_store_pd(lanes[7], _mm256_mul_pd(w_e, e));
  double* joint = s.joint + 3 * p;
  for (int j = 0; j < 4; ++j) {
    squares[S::kSquareSumT] += lanes[0][j];
    squares[S::kSquareSumR] += lanes[1][j];
    squares[S::kSquareSumE] += lanes[2][j];
    squares[S::kSquareRelative] += lanes[3][j];
    squares[S::kSquareWeightedE2] += lanes[4][j];
    joint[3 * j] += lanes[5][j];
    joint[3 * j + 1] += lanes[6][j];
    joint[3 * j + 2] += lanes[7][j];
  }

  if (!in.reference_stderr) return;
  const __m128 se = _mm_loadu_ps(in.reference_stderr + x);
  const __m128 finite32 = _mm_cmplt_ps(_mm_andnot_ps(_mm_set1_ps(-0.0f), se), _mm_set1_ps(HUGE_VALF));
  if (_mm_movemask_ps(finite32) == 0) return;
  const __m256d finite = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_castps_si128(finite32)));
  const __m256d se64 = _mm256_cvtps_pd(se);
  const __m256d s2 = _mm256_mul_pd(se64, se64);
  const __m256d two = _mm256_set1_pd(2.0);
  const __m256d slope = _mm256_sub_pd(
      _mm256_div_pd(_mm256_mul_pd(_mm256_set1_pd(-2.0), e), denominator),
      _mm256_div_pd(_mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(two, rv), e), e), _mm256_mul_pd(denominator, denominator)));
  AddWhere(s.noise + p, s2, finite);
  AddWhere(s.weighted_noise + p, _mm256_mul_pd(w, s2), finite);
  AddWhere(s.relmse_noise + p, _mm256_mul_pd(_mm256_mul_pd(slope, slope), s2), finite);
}

// Runs `pixels(x0, x1, squares)` over each tile's pixel range of the row,
// with the tile's sums zeroed first; `pixels` says whether any pixel entered.
template <class Pixels>
inline void ForEachTile(const CellRowInput& in, double* tile_squares, uint8_t* tile_any, Pixels pixels) {
  const int tiles = (in.width + in.tile - 1) / in.tile;
  for (int t = 0; t < tiles; ++t) {
    double* squares = tile_squares + static_cast<size_t>(t) * S::kSquareSums;
    std::fill(squares, squares + S::kSquareSums, 0.0);
    tile_any[t] = pixels(t * in.tile, std::min((t + 1) * in.tile, in.width), squares);
  }
}

}  // namespace

void UpdatePixelRow(const PixelRowInput& in, PixelRowState& state, PixelRowTerms& terms) {
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return UpdateRowAvx2(in, state, terms);
  UpdatePixelRowScalar(in, state, terms);
}

void UpdatePixelRowScalar(const PixelRowInput& in, PixelRowState& state, PixelRowTerms& terms) {
  for (int x = 0; x < in.width; ++x) UpdatePixel(in, state, terms, x);
}

__attribute__((target("avx2"))) static void AddCellRowAvx2(const CellRowInput& in, CellRowState& state,
                                                           double* tile_squares, uint8_t* tile_any) {
  ForEachTile(in, tile_squares, tile_any, [&](int x0, int x1, double* squares) __attribute__((target("avx2"))) {
    bool any = false;
    for (int x = x0; x < x1;) {
      uint32_t four = 0;
      if (x + 4 <= x1) std::memcpy(&four, in.updated + x, 4);
      if (four == 0x01010101u) {  // four updated pixels
        AddCellPixels4(in, state, x, squares);
        any = true;
        x += 4;
        continue;
      }
      if (in.updated[x]) {
        AddCellPixel(in, state, x, squares);
        any = true;
      }
      ++x;
    }
    return any;
  });
}

void AddCellRow(const CellRowInput& in, CellRowState& state, double* tile_squares, uint8_t* tile_any) {
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return AddCellRowAvx2(in, state, tile_squares, tile_any);
  AddCellRowScalar(in, state, tile_squares, tile_any);
}

void AddCellRowScalar(const CellRowInput& in, CellRowState& state, double* tile_squares, uint8_t* tile_any) {
  ForEachTile(in, tile_squares, tile_any, [&](int x0, int x1, double* squares) {
    bool any = false;
    for (int x = x0; x < x1; ++x)
      if (in.updated[x]) {
        AddCellPixel(in, state, x, squares);
        any = true;
      }
    return any;
  });
}

}  // namespace shimmer::metrics::detail
