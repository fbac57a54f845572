// Normal maps: the mip chain's moments and Toksvig factors, the procedural
// maps, PNG and EXR files and their errors, the cache (CPU only).
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "shimmer/renderer/normal_map.h"

namespace shimmer::scene {
namespace {

namespace fs = std::filesystem;

// Unit normals with slopes in [-0.6, 0.6]^2, fixed by `seed`.
std::vector<glm::dvec3> RandomNormals(int width, int height, unsigned seed) {
  std::mt19937 random(seed);
  auto slope = [&] { return 1.2 * (random() / 4294967296.0) - 0.6; };
  std::vector<glm::dvec3> normals;
  for (int i = 0; i < width * height; ++i) {
    const double x = slope(), y = slope();
    normals.push_back(glm::normalize(glm::dvec3(x, y, 1)));
  }
  return normals;
}

// Means over the level-0 texels that texel (x, y) of a level_w x level_h
// level covers, straight from the unit normals.
struct Means {
  glm::dvec3 n{0};
  glm::dvec2 t{0};
  glm::dvec3 tt{0};
};
Means BlockMeans(const std::vector<glm::dvec3>& normals, int width, int height, int level_w, int level_h, int x,
                 int y) {
  const int bw = width / level_w, bh = height / level_h;
  Means m;
  for (int j = y * bh; j < (y + 1) * bh; ++j)
    for (int i = x * bw; i < (x + 1) * bw; ++i) {
      const glm::dvec3 n = glm::normalize(normals[j * width + i]);
      const glm::dvec2 t = glm::dvec2(n) / n.z;
      m.n += n;
      m.t += t;
      m.tt += glm::dvec3(t.x * t.x, t.y * t.y, t.x * t.y);
    }
  const double count = bw * bh;
  m.n /= count;
  m.t /= count;
  m.tt /= count;
  return m;
}

NormalMapSource ProceduralSource(std::string name, double strength = 1) {
  NormalMapSource source;
  source.procedural = std::move(name);
  source.strength = strength;
  return source;
}

NormalMapSource FileSource(std::string file, double strength = 1) {
  NormalMapSource source;
  source.file = std::move(file);
  source.strength = strength;
  return source;
}

const NormalMapTexel& At(const NormalMapLevel& level, int x, int y) { return level.texels[y * level.width + x]; }

TEST(NormalMap, LevelsHalveDownToOneByOne) {
  auto square = BuildNormalMap("square", 256, 256, std::vector<glm::dvec3>(256 * 256, glm::dvec3(0, 0, 1)));
  ASSERT_TRUE(square.ok()) << square.error();
  ASSERT_EQ(square->levels.size(), 9u);
  for (int k = 0; k < 9; ++k) {
    EXPECT_EQ(square->levels[k].width, 256 >> k);
    EXPECT_EQ(square->levels[k].height, 256 >> k);
    EXPECT_EQ(square->levels[k].texels.size(), size_t(256 >> k) * (256 >> k));
  }
  // When one side is 1, only the other halves.
  auto wide = BuildNormalMap("wide", 8, 2, RandomNormals(8, 2, 1));
  ASSERT_TRUE(wide.ok()) << wide.error();
  const std::vector<std::pair<int, int>> sizes = {{8, 2}, {4, 1}, {2, 1}, {1, 1}};
  ASSERT_EQ(wide->levels.size(), sizes.size());
  for (size_t k = 0; k < sizes.size(); ++k) {
    EXPECT_EQ(wide->levels[k].width, sizes[k].first) << k;
    EXPECT_EQ(wide->levels[k].height, sizes[k].second) << k;
    EXPECT_EQ(wide->levels[k].texels.size(), size_t(sizes[k].first * sizes[k].second)) << k;
  }
  EXPECT_EQ(wide->name, "wide");
}

TEST(NormalMap, FlatMapHasNoSpreadAtAnyLevel) {
  auto map = BuildNormalMap("flat", 16, 8, std::vector<glm::dvec3>(16 * 8, glm::dvec3(0, 0, 2)));
  ASSERT_TRUE(map.ok()) << map.error();
  for (const NormalMapLevel& level : map->levels)
    for (const NormalMapTexel& t : level.texels) {
      EXPECT_NEAR(t.mean_normal.x, 0, 1e-6);
      EXPECT_NEAR(t.mean_normal.y, 0, 1e-6);
      EXPECT_NEAR(t.mean_normal.z, 1, 1e-6);  // normalised: the input was (0, 0, 2)
      EXPECT_NEAR(glm::length(t.b), 0, 1e-6);
      EXPECT_NEAR(glm::length(t.m), 0, 1e-6);
      EXPECT_NEAR(t.toksvig_ft, 1, 1e-6);
    }
}

TEST(NormalMap, MomentsAreBoxMeansOfTheLevelZeroTexels) {
  // Unnormalised on purpose: each texel is normalised before averaging.
  std::vector<glm::dvec3> normals = RandomNormals(4, 4, 7);
  for (size_t i = 0; i < normals.size(); ++i) normals[i] *= 0.5 + 0.25 * double(i % 5);
  auto map = BuildNormalMap("random", 4, 4, normals);
  ASSERT_TRUE(map.ok()) << map.error();
  ASSERT_EQ(map->levels.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    const NormalMapLevel& level = map->levels[k];
    for (int y = 0; y < level.height; ++y)
      for (int x = 0; x < level.width; ++x) {
        const Means want = BlockMeans(normals, 4, 4, level.width, level.height, x, y);
        const NormalMapTexel& got = At(level, x, y);
        for (int c = 0; c < 3; ++c) {
          EXPECT_NEAR(got.mean_normal[c], want.n[c], 1e-6) << "level " << k << " (" << x << ", " << y << ")";
          EXPECT_NEAR(got.m[c], want.tt[c], 1e-6) << "level " << k << " (" << x << ", " << y << ")";
        }
        for (int c = 0; c < 2; ++c) EXPECT_NEAR(got.b[c], want.t[c], 1e-6) << "level " << k;
      }
  }
  // The normals spread, so the coarsest mean normal is visibly shorter than 1.
  EXPECT_LT(glm::length(map->levels[2].texels[0].mean_normal), 0.99f);
}

// The Toksvig factor of every level against the seed-003 recipe done by hand:
// box means in double, a wrapped 5x5 Gaussian of sigma 1, ft = r / (r + s (1 - r)).
// 2x2 and 8x2 maps have levels narrower than the kernel (2x2, 2x1, 1x1, 4x1),
// where the wrap visits texels more than once.
TEST(NormalMap, ToksvigFactorIsTheFormulaOnAWrappedGaussian) {
  double weights[5], sum = 0;
  for (int i = 0; i < 5; ++i) sum += weights[i] = std::exp(-(i - 2) * (i - 2) / 2.0);
  for (double& w : weights) w /= sum;

  const std::vector<std::tuple<int, int, unsigned>> cases = {{2, 2, 11}, {8, 2, 12}, {4, 8, 13}};
  for (auto [width, height, seed] : cases) {
    const std::vector<glm::dvec3> normals = RandomNormals(width, height, seed);
    auto map = BuildNormalMap("toksvig", width, height, normals);
    ASSERT_TRUE(map.ok()) << map.error();
    for (size_t k = 0; k < map->levels.size(); ++k) {
      const NormalMapLevel& level = map->levels[k];
      const int lw = level.width, lh = level.height;
      for (int y = 0; y < lh; ++y)
        for (int x = 0; x < lw; ++x) {
          glm::dvec3 filtered(0);
          for (int j = -2; j <= 2; ++j)
            for (int i = -2; i <= 2; ++i) {
              const int sx = ((x + i) % lw + lw) % lw, sy = ((y + j) % lh + lh) % lh;
              filtered += weights[i + 2] * weights[j + 2] * BlockMeans(normals, width, height, lw, lh, sx, sy).n;
            }
          const double r = std::clamp(glm::length(filtered), 1e-6, 1.0);
          const double ft = r / (r + kToksvigFixedPower * (1 - r));
          EXPECT_NEAR(At(level, x, y).toksvig_ft, ft, 1e-6)
              << width << "x" << height << " level " << k << " (" << x << ", " << y << ")";
          EXPECT_LT(At(level, x, y).toksvig_ft, 0.99f);  // these normals spread by tens of degrees
          EXPECT_GT(At(level, x, y).toksvig_ft, 0.0f);
        }
    }
  }
}

TEST(NormalMap, RejectsBadSizesAndNormalsNamingTheTexel) {
  auto not_pow2 = BuildNormalMap("odd", 3, 4, std::vector<glm::dvec3>(12, glm::dvec3(0, 0, 1)));
  ASSERT_FALSE(not_pow2.ok());
  EXPECT_NE(not_pow2.error().find("odd"), std::string::npos) << not_pow2.error();
  EXPECT_NE(not_pow2.error().find("3x4"), std::string::npos) << not_pow2.error();
  EXPECT_EQ(not_pow2.code(), ErrorCode::kBadInput);

  auto empty = BuildNormalMap("empty", 0, 4, {});
  EXPECT_FALSE(empty.ok());
  auto huge = BuildNormalMap("huge", 2 * kMaxNormalMapSide, 1, {});
  ASSERT_FALSE(huge.ok());
  EXPECT_NE(huge.error().find(std::to_string(kMaxNormalMapSide)), std::string::npos) << huge.error();
  auto short_list = BuildNormalMap("short", 4, 4, std::vector<glm::dvec3>(15, glm::dvec3(0, 0, 1)));
  ASSERT_FALSE(short_list.ok());
  EXPECT_NE(short_list.error().find("15"), std::string::npos) << short_list.error();

  std::vector<glm::dvec3> normals(16, glm::dvec3(0.1, 0.2, 1));
  normals[2 * 4 + 3] = glm::dvec3(0);
  auto zero = BuildNormalMap("zero", 4, 4, normals);
  ASSERT_FALSE(zero.ok());
  EXPECT_NE(zero.error().find("zero: texel (3, 2)"), std::string::npos) << zero.error();
  EXPECT_NE(zero.error().find("zero-length"), std::string::npos) << zero.error();

  normals[2 * 4 + 3] = glm::dvec3(0.1, 0, 1);
  normals[1 * 4 + 0] = glm::dvec3(0.3, 0, -0.01);
  auto down = BuildNormalMap("down", 4, 4, normals);
  ASSERT_FALSE(down.ok());
  EXPECT_NE(down.error().find("down: texel (0, 1)"), std::string::npos) << down.error();
  normals[1 * 4 + 0] = glm::dvec3(1, 0, 0);  // sideways: z = 0 is not above the surface either
  EXPECT_FALSE(BuildNormalMap("sideways", 4, 4, normals).ok());

  normals[1 * 4 + 0] = glm::dvec3(0, std::nan(""), 1);
  auto nan = BuildNormalMap("nan", 4, 4, normals);
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.error().find("texel (0, 1)"), std::string::npos) << nan.error();
}

TEST(NormalMap, SourceNeedsExactlyOneOriginAndASaneStrength) {
  auto both = LoadNormalMap(NormalMapSource{"a.png", "bumps", 1});
  ASSERT_FALSE(both.ok());
  EXPECT_NE(both.error().find("a.png"), std::string::npos) << both.error();
  EXPECT_FALSE(LoadNormalMap({}).ok());
  for (double strength : {-0.5, 10.5, std::nan(""), std::numeric_limits<double>::infinity()}) {
    auto bad = LoadNormalMap(ProceduralSource("bumps", strength));
    ASSERT_FALSE(bad.ok()) << strength;
    EXPECT_NE(bad.error().find("strength"), std::string::npos) << bad.error();
  }
  EXPECT_TRUE(LoadNormalMap(ProceduralSource("bumps", 10)).ok());
  auto unknown = LoadNormalMap(ProceduralSource("bumpz"));
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().find("bumpz"), std::string::npos) << unknown.error();
  for (std::string_view name : ProceduralNormalMapNames())
    EXPECT_NE(unknown.error().find(std::string(name)), std::string::npos) << unknown.error();
}

// ---- Procedural maps ----

std::shared_ptr<const NormalMap> Procedural(const std::string& name, double strength = 1) {
  auto map = LoadNormalMap(ProceduralSource(name, strength));
  EXPECT_TRUE(map.ok()) << map.error();
  return map.ok() ? *map : std::make_shared<const NormalMap>();
}

TEST(ProceduralNormalMap, TheFourBuiltInsAre256SquareWithFullChains) {
  const std::vector<std::string_view> names = ProceduralNormalMapNames();
  EXPECT_EQ(names, (std::vector<std::string_view>{"bumps", "bumps-fine", "ridges", "patches"}));
  for (std::string_view name : names) {
    auto map = Procedural(std::string(name));
    ASSERT_EQ(map->levels.size(), 9u) << name;
    EXPECT_EQ(map->levels[0].width, 256);
    EXPECT_EQ(map->levels[0].height, 256);
    EXPECT_EQ(map->name, name);
    // Steepest slope about 0.35 at strength 1.
    float steepest = 0;
    for (const NormalMapTexel& t : map->levels[0].texels) steepest = std::max(steepest, glm::length(t.b));
    EXPECT_GT(steepest, 0.3f) << name;
    EXPECT_LT(steepest, 0.4f) << name;
  }
}

TEST(ProceduralNormalMap, MeanNormalShortensWithLevelAndVarianceIsNeverNegative) {
  for (std::string_view name : ProceduralNormalMapNames()) {
    auto map = Procedural(std::string(name));
    std::vector<double> mean_length;
    for (const NormalMapLevel& level : map->levels) {
      double sum = 0;
      for (const NormalMapTexel& t : level.texels) {
        const float length = glm::length(t.mean_normal);
        EXPECT_LE(length, 1 + 1e-6) << name;
        sum += length;
        // CLEAN's variance E[|t|^2] - |E[t]|^2.
        EXPECT_GE(t.m.x + t.m.y - glm::dot(t.b, t.b), -1e-6) << name << " level " << mean_length.size();
      }
      mean_length.push_back(sum / level.texels.size());
    }
    // |mean of four| <= mean of |four|: the average length cannot grow.
    for (size_t k = 1; k < mean_length.size(); ++k) EXPECT_LE(mean_length[k], mean_length[k - 1] + 1e-6) << name;
    if (name == "bumps") {
      EXPECT_LT(mean_length.back(), mean_length.front() - 1e-3);
    }
  }
}

TEST(ProceduralNormalMap, RidgesAreAnisotropicAndBumpsAreNot) {
  auto variances = [](const NormalMap& map) {
    const NormalMapTexel& t = map.levels.back().texels[0];
    return glm::dvec2(t.m.x - t.b.x * t.b.x, t.m.y - t.b.y * t.b.y);
  };
  const glm::dvec2 ridges = variances(*Procedural("ridges"));
  EXPECT_GT(ridges.y, 0);  // a little spread along v, so the ratio below is not 0 >= 0
  EXPECT_GE(ridges.x, 10 * ridges.y) << ridges.x << " vs " << ridges.y;
  const glm::dvec2 bumps = variances(*Procedural("bumps"));
  EXPECT_LT(bumps.x, 2 * bumps.y);
  EXPECT_LT(bumps.y, 2 * bumps.x);
}

TEST(ProceduralNormalMap, PatchesAreFlatOnTheRightHalfOnly) {
  auto map = Procedural("patches");
  const NormalMapLevel& level = map->levels[0];
  float steepest_left = 0;
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      const NormalMapTexel& t = At(level, x, y);
      if (x >= 128) {
        EXPECT_NEAR(t.mean_normal.x, 0, 1e-6) << x << ", " << y;
        EXPECT_NEAR(t.mean_normal.y, 0, 1e-6) << x << ", " << y;
        EXPECT_NEAR(t.mean_normal.z, 1, 1e-6) << x << ", " << y;
      } else {
        steepest_left = std::max(steepest_left, glm::length(t.b));
      }
      // Toksvig map: glossy (1) over the flat half away from the wrapped kernel's
      // reach, rougher (< 1) in the bumps' core.
      if (x >= 132 && x < 252) {
        EXPECT_NEAR(t.toksvig_ft, 1, 1e-6) << x << ", " << y;
      }
      if (x >= 40 && x < 88) {
        EXPECT_LT(t.toksvig_ft, 0.999f) << x << ", " << y;
      }
    }
  EXPECT_GT(steepest_left, 0.2f);
}

// A seam would show as a jump between the last and first column (row) larger
// than any step between neighbours inside the tile.
TEST(ProceduralNormalMap, TilesWithoutASeam) {
  for (std::string_view name : ProceduralNormalMapNames()) {
    auto map = Procedural(std::string(name));
    const NormalMapLevel& level = map->levels[0];
    auto normal = [&](int x, int y) { return glm::dvec3(At(level, x & 255, y & 255).mean_normal); };
    for (bool along_u : {true, false}) {
      auto step = [&](int i, int line) {
        return along_u ? glm::length(normal(i + 1, line) - normal(i, line))
                       : glm::length(normal(line, i + 1) - normal(line, i));
      };
      double largest_inside = 0, seam = 0;
      for (int i = 0; i < 255; ++i) {
        double mean = 0;
        for (int line = 0; line < 256; ++line) mean += step(i, line) / 256;
        largest_inside = std::max(largest_inside, mean);
      }
      for (int line = 0; line < 256; ++line) seam += step(255, line) / 256;
      EXPECT_LE(seam, 1.01 * largest_inside) << name << (along_u ? " along u" : " along v");
    }
    // Integer cycles per tile also make every wave's slope average to zero
    // over the texel grid (patches' mask breaks the symmetry).
    if (name != "patches") {
      EXPECT_LT(glm::length(map->levels.back().texels[0].b), 1e-5f) << name;
    }
  }
}

TEST(ProceduralNormalMap, StrengthScalesTheSlopes) {
  auto flat = Procedural("bumps", 0);
  for (const NormalMapLevel& level : flat->levels)
    for (const NormalMapTexel& t : level.texels) {
      EXPECT_NEAR(t.mean_normal.z, 1, 1e-6);
      EXPECT_NEAR(glm::length(t.b), 0, 1e-6);
      EXPECT_NEAR(t.toksvig_ft, 1, 1e-6);
    }
  auto one = Procedural("bumps", 1), two = Procedural("bumps", 2);
  ASSERT_NE(one, two);
  for (size_t i = 0; i < one->levels[0].texels.size(); ++i) {
    const NormalMapTexel &a = one->levels[0].texels[i], &b = two->levels[0].texels[i];
    EXPECT_NEAR(b.b.x, 2 * a.b.x, 1e-6);
    EXPECT_NEAR(b.b.y, 2 * a.b.y, 1e-6);
    EXPECT_NEAR(b.m.x, 4 * a.m.x, 1e-6);
  }
  // Steeper slopes spread the normals more.
  EXPECT_LT(two->levels.back().texels[0].toksvig_ft, one->levels.back().texels[0].toksvig_ft);
}

TEST(ProceduralNormalMap, CacheSharesOneMapPerSource) {
  auto a = LoadNormalMap(ProceduralSource("ridges"));
  auto b = LoadNormalMap(ProceduralSource("ridges"));
  auto c = LoadNormalMap(ProceduralSource("ridges", 0.5));
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_EQ(a->get(), b->get());
  EXPECT_NE(a->get(), c->get());
}

// ---- Files ----

class NormalMapFile : public ::testing::Test {
 protected:
  void SetUp() override {
    // Unique per process and test: the cache is keyed by path, so no two
    // tests may write different contents under one name.
    dir_ = fs::temp_directory_path() / ("shimmer_normal_map_test_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // Float R, G, B (x, y, z), row 0 first; without `blue` the B channel is left out.
  std::string WriteExr(const std::string& name, int width, int height, const std::vector<glm::vec3>& xyz,
                       bool blue = true) {
    const std::string file = Path(name);
    Imf::Header header(width, height);
    Imf::FrameBuffer buffer;
    const char* channels[] = {"R", "G", "B"};
    for (int c = 0; c < (blue ? 3 : 2); ++c) {
      header.channels().insert(channels[c], Imf::Channel(Imf::FLOAT));
      buffer.insert(
          channels[c],
          Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(xyz.data())) + c * sizeof(float),
                     sizeof(glm::vec3), sizeof(glm::vec3) * width));
    }
    Imf::OutputFile out(file.c_str(), header);
    out.setFrameBuffer(buffer);
    out.writePixels(height);
    return file;
  }

  std::string WriteBytes(const std::string& name, const std::string& bytes) {
    const std::string file = Path(name);
    std::ofstream(file, std::ios::binary) << bytes;
    return file;
  }

  std::string WriteImage(const std::string& name, const cv::Mat& image) {
    const std::string file = Path(name);
    EXPECT_TRUE(cv::imwrite(file, image)) << file;
    return file;
  }

  // The error of loading `file`, which must fail with a message naming it.
  std::string LoadError(const std::string& file) {
    auto map = LoadNormalMap(FileSource(file));
    EXPECT_FALSE(map.ok()) << file;
    if (map.ok()) return "";
    EXPECT_NE(map.error().find(file), std::string::npos) << map.error();
    EXPECT_EQ(map.code(), ErrorCode::kBadInput) << map.error();
    return map.error();
  }

  fs::path dir_;
};

// A smooth field of normals with slopes up to about +-0.45.
glm::dvec3 KnownNormal(int x, int y, int width, int height) {
  return glm::normalize(glm::dvec3((x - 0.5 * (width - 1)) / width, (y - 0.5 * (height - 1)) / (1.2 * height), 1));
}

template <class Channel>
void CheckPngRoundTrip(const NormalMap& map, const cv::Mat& image, double max) {
  const int channels = image.channels();
  ASSERT_EQ(map.levels[0].width, image.cols);
  ASSERT_EQ(map.levels[0].height, image.rows);
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) {
      const Channel* p = image.ptr<Channel>(y) + x * channels;
      const glm::dvec3 decoded = glm::normalize(glm::dvec3(2 * p[2] / max - 1, 2 * p[1] / max - 1, 2 * p[0] / max - 1));
      const glm::dvec3 original = KnownNormal(x, y, image.cols, image.rows);
      const glm::vec3 got = At(map.levels[0], x, y).mean_normal;
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(got[c], decoded[c], 1e-6) << x << ", " << y;
        EXPECT_NEAR(got[c], original[c], 2 / max) << x << ", " << y;  // quantisation, after normalising
      }
    }
}

TEST_F(NormalMapFile, EightBitPngRoundTrips) {
  cv::Mat image(4, 8, CV_8UC3);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x) {
      const glm::dvec3 n = KnownNormal(x, y, 8, 4);
      auto q = [](double c) { return cv::saturate_cast<std::uint8_t>(std::round((c + 1) / 2 * 255)); };
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(q(n.z), q(n.y), q(n.x));  // BGR
    }
  auto map = LoadNormalMap(FileSource(WriteImage("eight.PNG", image)));
  ASSERT_TRUE(map.ok()) << map.error();
  CheckPngRoundTrip<std::uint8_t>(**map, image, 255);
  ASSERT_EQ((*map)->levels.size(), 4u);
}

TEST_F(NormalMapFile, SixteenBitPngWithAlphaRoundTrips) {
  cv::Mat image(8, 4, CV_16UC4);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 4; ++x) {
      const glm::dvec3 n = KnownNormal(x, y, 4, 8);
      auto q = [](double c) { return cv::saturate_cast<std::uint16_t>(std::round((c + 1) / 2 * 65535)); };
      image.at<cv::Vec4w>(y, x) = cv::Vec4w(q(n.z), q(n.y), q(n.x), std::uint16_t(x * 1000));  // BGRA
    }
  auto map = LoadNormalMap(FileSource(WriteImage("sixteen.png", image)));
  ASSERT_TRUE(map.ok()) << map.error();
  CheckPngRoundTrip<std::uint16_t>(**map, image, 65535);
}

TEST_F(NormalMapFile, ExrRoundTripsToFloatPrecision) {
  std::vector<glm::vec3> xyz;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 16; ++x) xyz.push_back(glm::vec3(KnownNormal(x, y, 16, 4)));
  auto map = LoadNormalMap(FileSource(WriteExr("float.exr", 16, 4, xyz)));
  ASSERT_TRUE(map.ok()) << map.error();
  ASSERT_EQ((*map)->levels[0].width, 16);
  for (size_t i = 0; i < xyz.size(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR((*map)->levels[0].texels[i].mean_normal[c], xyz[i][c], 1e-7) << i;

  // Strength applies to files too, and the cache hands out one map per source.
  auto again = LoadNormalMap(FileSource(Path("float.exr")));
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->get(), map->get());
  auto doubled = LoadNormalMap(FileSource(Path("float.exr"), 2));
  ASSERT_TRUE(doubled.ok()) << doubled.error();
  const NormalMapTexel &a = (*map)->levels[0].texels[5], &b = (*doubled)->levels[0].texels[5];
  EXPECT_NEAR(b.b.x, 2 * a.b.x, 1e-6);
  EXPECT_NEAR(b.b.y, 2 * a.b.y, 1e-6);
}

TEST_F(NormalMapFile, BadFilesGiveOneMessageNamingTheFile) {
  EXPECT_NE(LoadError(Path("missing.png")).find("no such file"), std::string::npos);
  EXPECT_NE(LoadError(WriteBytes("garbage.png", "this is not a PNG at all, just bytes")).find("not a PNG"),
            std::string::npos);
  // A real PNG signature and header, then a truncated body.
  cv::Mat good(4, 4, CV_8UC3, cv::Scalar(255, 128, 128));
  std::vector<uchar> bytes;
  cv::imencode(".png", good, bytes);
  EXPECT_NE(LoadError(WriteBytes("truncated.png", std::string(bytes.begin(), bytes.begin() + 40))).find("readable"),
            std::string::npos);
  EXPECT_NE(LoadError(WriteImage("gray.png", cv::Mat(4, 4, CV_8UC1, cv::Scalar(200)))).find("1 channel"),
            std::string::npos);
  EXPECT_NE(LoadError(WriteImage("three.png", cv::Mat(4, 3, CV_8UC3, cv::Scalar(255, 128, 128)))).find("3x4"),
            std::string::npos);
  EXPECT_NE(LoadError(WriteImage("wide.png", cv::Mat(1, 2 * kMaxNormalMapSide, CV_8UC3, cv::Scalar(255, 128, 128))))
                .find(std::to_string(kMaxNormalMapSide)),
            std::string::npos);
  EXPECT_NE(LoadError(WriteBytes("normals.tga", "TGA")).find(".png"), std::string::npos);
  fs::create_directories(Path("folder.png"));
  EXPECT_NE(LoadError(Path("folder.png")).find("directory"), std::string::npos);

  // Blue 0 decodes to z = -1.
  cv::Mat under(2, 2, CV_8UC3, cv::Scalar(255, 128, 128));
  under.at<cv::Vec3b>(1, 0) = cv::Vec3b(0, 128, 128);
  const std::string under_error = LoadError(WriteImage("under.png", under));
  EXPECT_NE(under_error.find("texel (0, 1)"), std::string::npos) << under_error;

  std::vector<glm::vec3> xyz(4, glm::vec3(0, 0, 1));
  xyz[1] = glm::vec3(0);
  const std::string zero = LoadError(WriteExr("zero.exr", 2, 2, xyz));
  EXPECT_NE(zero.find("texel (1, 0)"), std::string::npos) << zero;
  EXPECT_NE(zero.find("zero-length"), std::string::npos) << zero;
  xyz[1] = glm::vec3(0, 0, 1);
  xyz[3] = glm::vec3(0.2, 0.1, -0.5);
  const std::string down = LoadError(WriteExr("down.exr", 2, 2, xyz));
  EXPECT_NE(down.find("texel (1, 1)"), std::string::npos) << down;
  EXPECT_NE(down.find("z > 0"), std::string::npos) << down;
  EXPECT_NE(LoadError(WriteExr("no_blue.exr", 2, 2, xyz, false)).find("no B channel"), std::string::npos);
  EXPECT_NE(LoadError(WriteExr("odd.exr", 3, 2, std::vector<glm::vec3>(6, glm::vec3(0, 0, 1)))).find("3x2"),
            std::string::npos);
  EXPECT_NE(LoadError(WriteBytes("garbage.exr", "not an EXR")).find("garbage.exr"), std::string::npos);
}

}  // namespace
}  // namespace shimmer::scene
