// The metrics pass's per-row kernel: its AVX2 lanes against the one-pixel
// code they replace, bit for bit, over frames that mix every case a lane can
// be in (outside the region, NaN or infinite in either sequence, excluded by
// an earlier frame, ordinary), with widths that leave a scalar tail.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "../../metrics/src/pixel_row.h"

namespace shimmer::metrics::detail {
namespace {

// Everything one row of UpdatePixelRow reads and writes, for one width.
struct RowBuffers {
  explicit RowBuffers(int width)
      : width(width),
        test(width, 1),
        reference(width, 1),
        error(width, 1),
        excluded(width),
        diff_test(width),
        diff_error(width),
        signal(width, -7.0f),  // outside the region the signal stays as it was
        terms(4 * width),
        updated(width) {}

  PixelRowState State() {
    return {.excluded = excluded.data(),
            .test = test.At(0),
            .reference = reference.At(0),
            .error = error.At(0),
            .diff_test = diff_test.data(),
            .diff_error = diff_error.data(),
            .signal = signal.data()};
  }
  PixelRowTerms Terms() {
    return {.test = terms.data(),
            .reference = terms.data() + width,
            .error2 = terms.data() + 2 * width,
            .relative2 = terms.data() + 3 * width,
            .updated = updated.data()};
  }

  int width;
  TemporalMoments test, reference, error;
  std::vector<uint8_t> excluded;
  std::vector<double> diff_test, diff_error;
  std::vector<float> signal;
  std::vector<double> terms;
  std::vector<uint8_t> updated;
};

template <class T>
bool SameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

bool SameMoments(const TemporalMoments& a, const TemporalMoments& b, int width) {
  for (int x = 0; x < width; ++x) {
    const double ma = a.mean(x), mb = b.mean(x), va = a.variance(x), vb = b.variance(x);
    if (a.count(x) != b.count(x) || std::memcmp(&ma, &mb, sizeof ma) || std::memcmp(&va, &vb, sizeof va)) return false;
  }
  return true;
}

float Sample(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0, 1);
  const float pick = u(rng);
  if (pick < 0.03f) return std::numeric_limits<float>::quiet_NaN();
  if (pick < 0.05f) return (pick < 0.04f ? 1 : -1) * std::numeric_limits<float>::infinity();
  // Highlights span decades: exercise the relMSE denominator at both ends.
  return std::exp(12 * u(rng) - 8) * (u(rng) < 0.1f ? -1 : 1);
}

class PixelRowLanes : public ::testing::TestWithParam<bool> {};  // with a reference

TEST_P(PixelRowLanes, MatchTheOnePixelCodeBitForBit) {
  if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "no AVX2: UpdatePixelRow is the one-pixel code itself";
  const bool with_reference = GetParam();
  for (const int width : {1, 4, 7, 64, 131}) {
    std::mt19937 rng(1234 + width);
    RowBuffers vector_row(width), scalar_row(width);
    std::vector<uint8_t> region(width);
    for (auto& r : region) r = rng() % 5 != 0;
    std::vector<float> test(width), reference(width), previous_test, previous_reference;
    long long samples = 0, non_finite = 0;
    for (int frame = 0; frame < 12; ++frame) {
      for (int x = 0; x < width; ++x) {
        test[x] = Sample(rng);
        reference[x] = Sample(rng);
      }
      for (const bool signal_error : {false, true}) {
        if (signal_error != (frame % 3 == 0)) continue;  // both signals, on different frames
        const PixelRowInput in{.width = width,
                               .test = test.data(),
                               .reference = with_reference ? reference.data() : nullptr,
                               .previous_test = frame ? previous_test.data() : nullptr,
                               .previous_reference = frame && with_reference ? previous_reference.data() : nullptr,
                               .region = region.data(),
                               .signal_error = signal_error};
        PixelRowState vector_state = vector_row.State(), scalar_state = scalar_row.State();
        PixelRowTerms vector_terms = vector_row.Terms(), scalar_terms = scalar_row.Terms();
        UpdatePixelRow(in, vector_state, vector_terms);
        UpdatePixelRowScalar(in, scalar_state, scalar_terms);
        SCOPED_TRACE("width " + std::to_string(width) + ", frame " + std::to_string(frame));
        EXPECT_EQ(vector_terms.samples, scalar_terms.samples);
        EXPECT_EQ(vector_terms.non_finite, scalar_terms.non_finite);
        samples += scalar_terms.samples;
        non_finite += scalar_terms.non_finite;
      }
      ASSERT_TRUE(SameBits(vector_row.terms, scalar_row.terms));
      ASSERT_TRUE(SameBits(vector_row.updated, scalar_row.updated));
      ASSERT_TRUE(SameBits(vector_row.excluded, scalar_row.excluded));
      ASSERT_TRUE(SameBits(vector_row.diff_test, scalar_row.diff_test));
      ASSERT_TRUE(SameBits(vector_row.diff_error, scalar_row.diff_error));
      ASSERT_TRUE(SameBits(vector_row.signal, scalar_row.signal));
      ASSERT_TRUE(SameMoments(vector_row.test, scalar_row.test, width));
      ASSERT_TRUE(SameMoments(vector_row.reference, scalar_row.reference, width));
      ASSERT_TRUE(SameMoments(vector_row.error, scalar_row.error, width));
      previous_test = test;
      previous_reference = reference;
    }
    // The draw reached every case: pixels that count, and NaN/inf that do not.
    EXPECT_GT(samples, 0);
    if (width >= 64) {
      EXPECT_GT(non_finite, 0);
    }
  }
}

// AddCellRow's lanes against its one-pixel code: rows with region holes and
// pixels not updated (so four-pixel runs start anywhere), reference noise
// that is sometimes NaN or infinite or absent, tiles that are not a multiple
// of four wide, and the first frame's shifts.
TEST(CellRowLanes, MatchTheOnePixelCodeBitForBit) {
  if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "no AVX2: AddCellRow is the one-pixel code itself";
  constexpr int kSums = TileBlockStatistics::kPixelSums, kSquares = TileBlockStatistics::kSquareSums;
  for (const int width : {3, 9, 64, 131})
    for (const int tile : {4, 6, 8}) {
      std::mt19937 rng(99 + width * 10 + tile);
      std::vector<int> region_index(width, -1);
      int pixels = 0;
      for (auto& index : region_index)
        if (rng() % 6 != 0) index = pixels++;
      struct Sums {
        std::vector<float> shifts, cells;
        std::vector<double> joint, noise, weighted_noise, relmse_noise, squares;
        std::vector<uint8_t> any;
        CellRowState State() {
          return {shifts.data(), cells.data(), joint.data(), noise.data(), weighted_noise.data(), relmse_noise.data()};
        }
      };
      const int tiles = (width + tile - 1) / tile;
      Sums vector_sums{std::vector<float>(2 * pixels), std::vector<float>(kSums * pixels),
                       std::vector<double>(3 * pixels), std::vector<double>(pixels), std::vector<double>(pixels),
                       std::vector<double>(pixels), std::vector<double>(kSquares * tiles), std::vector<uint8_t>(tiles)};
      Sums scalar_sums = vector_sums;
      std::vector<float> test(width), reference(width), noise(width);
      std::vector<uint8_t> updated(width);
      std::vector<double> relative2(width);
      int runs_of_four = 0;
      for (int frame = 0; frame < 10; ++frame) {
        std::uniform_real_distribution<float> u(0, 1);
        for (int x = 0; x < width; ++x) {
          updated[x] = region_index[x] >= 0 && u(rng) < 0.9f;
          test[x] = std::exp(12 * u(rng) - 8) * (u(rng) < 0.1f ? -1 : 1);
          reference[x] = std::exp(12 * u(rng) - 8);
          const float pick = u(rng);
          noise[x] = pick < 0.05f ? std::numeric_limits<float>::quiet_NaN()
                     : pick < 0.08f ? std::numeric_limits<float>::infinity()
                                    : 0.01f * reference[x] * u(rng);
          const double e = double(test[x]) - reference[x];
          relative2[x] = e * e / (double(reference[x]) * reference[x] + kRelMseEpsilon);
        }
        for (int x = 0; x + 4 <= width; ++x)
          runs_of_four += updated[x] && updated[x + 1] && updated[x + 2] && updated[x + 3];
        const CellRowInput in{.width = width,
                              .tile = tile,
                              .test = test.data(),
                              .reference = reference.data(),
                              .reference_stderr = frame % 4 == 3 ? nullptr : noise.data(),
                              .region_index = region_index.data(),
                              .updated = updated.data(),
                              .relative2 = relative2.data(),
                              .first_frame = frame == 0};
        CellRowState vector_state = vector_sums.State(), scalar_state = scalar_sums.State();
        AddCellRow(in, vector_state, vector_sums.squares.data(), vector_sums.any.data());
        AddCellRowScalar(in, scalar_state, scalar_sums.squares.data(), scalar_sums.any.data());
        SCOPED_TRACE("width " + std::to_string(width) + ", tile " + std::to_string(tile) + ", frame " +
                     std::to_string(frame));
        ASSERT_TRUE(SameBits(vector_sums.shifts, scalar_sums.shifts));
        ASSERT_TRUE(SameBits(vector_sums.cells, scalar_sums.cells));
        ASSERT_TRUE(SameBits(vector_sums.joint, scalar_sums.joint));
        ASSERT_TRUE(SameBits(vector_sums.noise, scalar_sums.noise));
        ASSERT_TRUE(SameBits(vector_sums.weighted_noise, scalar_sums.weighted_noise));
        ASSERT_TRUE(SameBits(vector_sums.relmse_noise, scalar_sums.relmse_noise));
        ASSERT_TRUE(SameBits(vector_sums.squares, scalar_sums.squares));
        ASSERT_TRUE(SameBits(vector_sums.any, scalar_sums.any));
      }
      // The sums moved, and the lanes ran.
      double total = 0;
      for (double j : scalar_sums.joint) total += j;
      EXPECT_GT(total, 0);
      if (width >= 64) {
        EXPECT_GT(runs_of_four, 0);
      }
    }
}

INSTANTIATE_TEST_SUITE_P(Reference, PixelRowLanes, ::testing::Bool(),
                         [](const auto& info) { return info.param ? "WithReference" : "TestOnly"; });

}  // namespace
}  // namespace shimmer::metrics::detail
