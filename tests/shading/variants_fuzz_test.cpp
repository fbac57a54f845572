// Hostile input for every variant: a fixed-seed random campaign of hard float
// (and, for a subset, double) inputs through EvaluateVariant, asserting that no
// output is NaN, Inf or negative. Inputs: alpha 0..10 with exact zeros and
// denormals, slopes and derivatives up to 1e20 with random signs and exact
// zeros, unit normals at grazing and below the horizon, and every parameter
// drawn from its valid range (ParamFields()), 0 and the upper bound included.
//
// The values come from precomputed pools picked by 16-bit slices of
// mt19937_64 words, so that generating an input costs eight generator calls
// and table lookups, and the campaign's 10^6 inputs per variant and NDF fit
// the time budget.
#include <gtest/gtest.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "shimmer/shading/shading.h"

namespace shimmer::shading {
namespace {

constexpr int kFloatInputs = 1'000'000;  // per variant and NDF
constexpr int kDoubleInputs = 100'000;

// `count` magnitudes: the values where the core changes regime (its clamps
// ALPHA_MIN, ALPHA_MAX, FOOTPRINT_MAX, SLOPE_MAX and their neighbours), zero,
// denormals, then log-uniform values over [1e-45, top] (for float the lowest
// are denormal or round to zero) and a block of ordinary values.
template <class T>
std::vector<T> MagnitudePool(std::mt19937_64& rng, int count, double top, std::vector<double> specials) {
  const T denorm = std::numeric_limits<T>::denorm_min(), tiny = std::numeric_limits<T>::min();
  for (double s : {0.0,
                   double(denorm),
                   double(denorm) * 3,
                   double(tiny) * 0.5,
                   double(tiny),
                   1e-30,
                   1e-20,
                   1e-12,
                   1e-8,
                   1e-4,
                   1e-3,
                   0.01,
                   0.1,
                   0.5,
                   1.0,
                   2.0,
                   10.0,
                   100.0,
                   1e4,
                   1e8,
                   1e16,
                   1e19,
                   1e20})
    specials.push_back(s);
  std::vector<T> pool;
  for (double s : specials)
    if (s <= top) {
      const T v = T(s);
      pool.push_back(v);
      pool.push_back(std::nextafter(v, T(0)));
      if (std::nextafter(v, T(top)) <= T(top)) pool.push_back(std::nextafter(v, T(top)));
    }
  std::uniform_real_distribution<double> u01(0, 1);
  const double lo = -45, hi = std::log10(top);
  // A quarter of the pool repeats the specials, so each is drawn often.
  for (std::size_t i = 0; pool.size() < std::size_t(count) / 4; ++i) pool.push_back(pool[i]);
  while (pool.size() < std::size_t(count) * 3 / 4) pool.push_back(T(std::pow(10.0, lo + (hi - lo) * u01(rng))));
  while (pool.size() < std::size_t(count)) pool.push_back(T(std::min(top, std::pow(10.0, -3 + 4 * u01(rng)))));
  return pool;
}

// Unit normals: two thirds within 1e-3 of the horizon (n.z exactly 0,
// +-denormal, +-1e-7, ...), the rest uniform over the sphere, so about half of
// all below the horizon.
template <class T>
std::vector<glm::vec<3, T>> NormalPool(std::mt19937_64& rng, int count) {
  std::uniform_real_distribution<double> u01(0, 1);
  const double zs[] = {0.0, 1e-310, -1e-310, 1e-40, -1e-40, 1e-7, -1e-7, 1e-3, -1e-3, 1.0, -1.0};
  std::vector<glm::vec<3, T>> pool;
  for (int i = 0; i < count; ++i) {
    double z;
    if (i % 3 == 0)
      z = zs[(i / 3) % std::size(zs)];
    else if (i % 3 == 1)
      z = 1e-3 * (2 * u01(rng) - 1);
    else
      z = 2 * u01(rng) - 1;
    const double phi = 2 * 3.14159265358979323846 * u01(rng), r = std::sqrt(std::max(0.0, 1 - z * z));
    pool.push_back({T(r * std::cos(phi)), T(r * std::sin(phi)), T(z)});
  }
  return pool;
}

template <class T>
struct Pools {
  std::vector<T> alpha;  // [0, 10]
  std::vector<T> value;  // [-1e20, 1e20]
  std::vector<glm::vec<3, T>> normal;
  std::vector<std::vector<T>> param;  // per ParamFields() entry, [lower, upper]

  explicit Pools(std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    alpha = MagnitudePool<T>(rng, 1 << 16, 10, {1e-7, 0.03, 0.999999, 5});
    value = MagnitudePool<T>(rng, 1 << 15, 1e20, {0.7, 5e3, 1e5, 1e10, 1e18});
    for (std::size_t i = 0, n = value.size(); i < n; ++i) value.push_back(-value[i]);
    normal = NormalPool<T>(rng, 1 << 12);
    for (const ParamField& r : ParamFields()) {
      std::vector<double> specials = {r.lo, r.hi};
      for (const VariantInfo& v : Variants())
        for (const ParamInfo& p : v.params)
          if (p.name == r.name) specials.push_back(p.default_value);
      std::vector<T> pool = MagnitudePool<T>(rng, 1 << 12, r.hi, specials);
      // A range reaching below zero (a bias) draws negative values as often.
      if (r.lo < 0)
        for (std::size_t i = 0, n = pool.size(); i < n; ++i) pool.push_back(-pool[i]);
      // Pools keep a power-of-two size (picks are masks, not divisions).
      std::vector<T> valid;
      for (T x : pool)
        if (ValidateParam(r.name, double(x)).ok()) valid.push_back(x);
      for (std::size_t i = 0; valid.size() < pool.size(); ++i) valid.push_back(valid[i]);
      param.push_back(valid);
    }
  }
};

// Draws inputs: eight 64-bit words of the generator give the 32 16-bit picks
// of one input, each an index into a pool (every pool's size is a power of two).
template <class T>
class InputGenerator {
 public:
  InputGenerator(const Pools<T>& pools, std::uint64_t seed) : pools_(pools), rng_(seed) {
    for (const ParamField& r : ParamFields())
      members_.push_back(r.name == "fp_max"       ? &Params<T>::fp_max
                         : r.name == "fp_min_cap" ? &Params<T>::fp_min_cap
                         : r.name == "sigma2"     ? &Params<T>::sigma2
                                                  : &Params<T>::kappa);
  }

  void Next(glm::vec<2, T>& alpha, Footprint<T>& f, Params<T>& p) {
    std::uint16_t b[32];
    for (int i = 0; i < 8; ++i) {
      const std::uint64_t w = rng_();
      for (int j = 0; j < 4; ++j) b[4 * i + j] = std::uint16_t(w >> (16 * j));
    }
    const std::uint16_t shape = b[0];
    alpha = {Alpha(b[1]), (shape & 1) ? Alpha(b[1]) : Alpha(b[2])};
    f.hpp = {Value(b[3]), Value(b[4])};
    f.dhpp_dx = {Value(b[5]), Value(b[6])};
    f.dhpp_dy = {Value(b[7]), Value(b[8])};
    // Rank-deficient footprints (the parallelogram's det R -> 0) and zero ones.
    if (shape & 2) f.dhpp_dy = f.dhpp_dx * (Alpha(b[9]) * T((shape & 0x200) ? -0.1 : 0.1));
    if ((shape & 0x1c) == 0) f.dhpp_dx = f.dhpp_dy = glm::vec<2, T>(0);
    // A half vector along the footprint, far out: where R^-1's form cancels.
    if ((shape & 0xc00) == 0) {
      const glm::vec<2, T> limit(T(1e20));
      f.hpp = glm::clamp(f.dhpp_dx * (Alpha(b[10]) * T((shape & 0x1000) ? -1e6 : 1e6)), -limit, limit);
    }
    // tk19-forward's projected derivatives: chained as an analytic footprint
    // has them, or raw (a quad difference is at most 2, raw values test the caps).
    if (shape & 0x2000) {
      f = WithChainedProjection(f);
    } else {
      f.dh_dx = f.dhpp_dx;
      f.dh_dy = f.dhpp_dy;
    }
    f.n = pools_.normal[b[11] & (pools_.normal.size() - 1)];
    f.dn_dx = {Value(b[12]), Value(b[13]), Value(b[14])};
    f.dn_dy = {Value(b[15]), Value(b[16]), Value(b[17])};
    if ((shape & 0xe0) == 0) f.dn_dx = f.dn_dy = glm::vec<3, T>(0);
    f.dng_dx = {Value(b[18]), Value(b[19]), Value(b[20])};
    f.dng_dy = {Value(b[21]), Value(b[22]), Value(b[23])};
    if (shape & 0x100) f.dng_dx = f.dn_dx, f.dng_dy = f.dn_dy;
    for (std::size_t i = 0; i < members_.size(); ++i)
      p.*members_[i] = pools_.param[i][b[24 + i] & (pools_.param[i].size() - 1)];
  }

 private:
  T Alpha(std::uint16_t b) const { return pools_.alpha[b & (pools_.alpha.size() - 1)]; }
  T Value(std::uint16_t b) const { return pools_.value[b & (pools_.value.size() - 1)]; }

  const Pools<T>& pools_;
  std::mt19937_64 rng_;
  std::vector<T Params<T>::*> members_;
};

template <class T>
bool Good(T x) {
  return std::isfinite(x) && x >= 0;
}

template <class T>
std::string Describe(const VariantInfo& v, Ndf ndf, int index, glm::vec<2, T> a, const Footprint<T>& f,
                     const Params<T>& p, const FilteredNdf<T>& r) {
  auto s = [](T x) {
    char b[48];
    std::snprintf(b, sizeof b, "%.17g", double(x));
    return std::string(b);
  };
  auto v2 = [&](glm::vec<2, T> x) { return "(" + s(x.x) + ", " + s(x.y) + ")"; };
  auto v3 = [&](glm::vec<3, T> x) { return "(" + s(x.x) + ", " + s(x.y) + ", " + s(x.z) + ")"; };
  return std::string(v.name) + " " + std::string(NdfName(ndf)) + " " + (sizeof(T) == 4 ? "float" : "double") +
         " input #" + std::to_string(index) + ": alpha " + v2(a) + " hpp " + v2(f.hpp) + " dhpp_dx " + v2(f.dhpp_dx) +
         " dhpp_dy " + v2(f.dhpp_dy) + " n " + v3(f.n) + " dn_dx " + v3(f.dn_dx) + " dn_dy " + v3(f.dn_dy) +
         " dng_dx " + v3(f.dng_dx) + " dng_dy " + v3(f.dng_dy) + " fp_max " + s(p.fp_max) + " fp_min_cap " +
         s(p.fp_min_cap) + " sigma2 " + s(p.sigma2) + " kappa " + s(p.kappa) + " -> slope_density " +
         s(r.slope_density) + " density " + s(r.density) + " alpha_eff " + v2(r.alpha_eff);
}

template <class T>
const Pools<T>& SharedPools() {
  static const Pools<T> pools(sizeof(T) == 4 ? 0x5eed0f10a7ull : 0x5eedd0b1eull);
  return pools;
}

// Runs `count` inputs of variant `v` with each NDF and expects every output finite and >= 0.
template <class T>
void Campaign(const VariantInfo& v, int count) {
  const Pools<T>& pools = SharedPools<T>();
  // Both NDFs for every variant: the GGX-only ones must not break on Beckmann either.
  for (Ndf ndf : {Ndf::kGgx, Ndf::kBeckmann, Ndf::kBlinnPhong}) {
    InputGenerator<T> gen(
        pools, 0x9e3779b97f4a7c15ull * std::uint64_t(v.id + 1) + std::uint64_t(ndf) + (sizeof(T) == 4 ? 0 : 0x100));
    glm::vec<2, T> alpha;
    Footprint<T> f;
    Params<T> p;
    long bad = 0;
    std::string first;
    for (int i = 0; i < count; ++i) {
      gen.Next(alpha, f, p);
      const FilteredNdf<T> r = EvaluateVariant<T>(v.id, ndf, alpha, f, p);
      if (Good(r.slope_density) && Good(r.density) && Good(r.alpha_eff.x) && Good(r.alpha_eff.y)) continue;
      if (bad++ == 0) first = Describe(v, ndf, i, alpha, f, p, r);
    }
    EXPECT_EQ(bad, 0) << bad << " of " << count << " outputs NaN, Inf or negative; the first:\n" << first;
  }
}

class VariantFuzz : public ::testing::TestWithParam<int> {};

TEST_P(VariantFuzz, FloatOutputsAreFiniteAndNonNegative) {
  const VariantInfo& v = Variants()[std::size_t(GetParam())];
  const auto start = std::chrono::steady_clock::now();
  Campaign<float>(v, kFloatInputs);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%-28s 2 NDFs x %d float inputs in %.2f s\n", std::string(v.name).c_str(), kFloatInputs, s);
}

TEST_P(VariantFuzz, DoubleOutputsAreFiniteAndNonNegative) {
  Campaign<double>(Variants()[std::size_t(GetParam())], kDoubleInputs);
}

INSTANTIATE_TEST_SUITE_P(Catalogue, VariantFuzz, ::testing::Range(0, int(Variants().size())),
                         [](const ::testing::TestParamInfo<int>& info) {
                           std::string name(Variants()[std::size_t(info.param)].name);
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

// The generator reaches what it claims to: the pools hold exact zeros,
// denormals and the extremes, and every parameter's pool its bounds.
TEST(VariantFuzzInputs, PoolsCoverTheHardCases) {
  const Pools<float>& pools = SharedPools<float>();
  auto has = [](const std::vector<float>& pool, auto pred) {
    for (float x : pool)
      if (pred(x)) return true;
    return false;
  };
  EXPECT_TRUE(has(pools.alpha, [](float x) { return x == 0; }));
  EXPECT_TRUE(has(pools.alpha, [](float x) { return x > 0 && x < std::numeric_limits<float>::min(); }));
  EXPECT_TRUE(has(pools.alpha, [](float x) { return x == 10; }));
  EXPECT_FALSE(has(pools.alpha, [](float x) { return !(x >= 0 && x <= 10); }));
  EXPECT_TRUE(has(pools.value, [](float x) { return x == 0; }));
  EXPECT_TRUE(has(pools.value, [](float x) { return x == 1e20f; }));
  EXPECT_TRUE(has(pools.value, [](float x) { return x == -1e20f; }));
  EXPECT_FALSE(has(pools.value, [](float x) { return !(std::abs(x) <= 1e20f); }));
  int grazing = 0, below = 0;
  for (const glm::vec3& n : pools.normal) {
    grazing += std::abs(n.z) < 1e-3f;
    below += n.z < 0;
    EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f);
  }
  EXPECT_GT(grazing, int(pools.normal.size()) / 4);
  EXPECT_GT(below, int(pools.normal.size()) / 3);
  ASSERT_EQ(pools.param.size(), ParamFields().size());
  for (std::size_t i = 0; i < pools.param.size(); ++i) {
    const ParamField& r = ParamFields()[i];
    EXPECT_TRUE(has(pools.param[i], [&](float x) { return x == float(r.lo); })) << r.name;
    EXPECT_TRUE(has(pools.param[i], [&](float x) { return x == float(r.hi); })) << r.name;
    EXPECT_FALSE(has(pools.param[i], [&](float x) { return !ValidateParam(r.name, x).ok(); })) << r.name;
  }
}

}  // namespace
}  // namespace shimmer::shading
