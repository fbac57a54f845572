// ZIP and ZIPS chunks inflated by libdeflate (core/src/zip_chunk.h) give
// exactly the pixels of OpenEXR's own decoding: its core library's zlib path
// in ExrInput, and its C++ library, an independent reader.
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "shimmer/core/exr_input.h"
#include "temp_dir.h"

namespace shimmer {
namespace {

struct ProbeChannel {
  std::string name;
  Imf::PixelType type;
};

// Channels of every pixel type, in an order the file sorts; values that
// compress well (smooth) next to values that do not (noise, so that some
// chunks are stored raw), with NaN, infinities and signed zeros among them.
const std::vector<ProbeChannel> kChannels = {
    {"A", Imf::HALF}, {"B", Imf::FLOAT}, {"C", Imf::UINT}, {"specular.R", Imf::FLOAT}, {"specular.Y", Imf::HALF}};

float Value(size_t channel, int x, int y, int width, std::mt19937& noise) {
  if (x == 1 && y == 0) return std::numeric_limits<float>::quiet_NaN();
  if (x == 2 && y == 0) return -std::numeric_limits<float>::infinity();
  if (x == 3 && y == 0) return -0.0f;
  if (y % 5 == 3) return std::uniform_real_distribution<float>(-1e4f, 1e4f)(noise);
  return std::sin(0.37f * x + 0.11f * y * (channel + 1)) * (1.0f + 3.0f * channel) + 0.001f * (y * width + x);
}

enum class Storage { kScanlines, kTiles };

// Writes with OpenEXR's C++ library; the data window's corner is (-3, 5).
void WriteProbe(const std::filesystem::path& file, int w, int h, Imf::Compression compression, Storage storage) {
  const Imath::Box2i window({-3, 5}, {-3 + w - 1, 5 + h - 1});
  Imf::Header header(window, window);
  header.compression() = compression;
  std::mt19937 noise(w * 131 + h);
  std::vector<std::vector<float>> floats;
  std::vector<std::vector<Imath::half>> halves;
  std::vector<std::vector<unsigned>> uints;
  Imf::FrameBuffer buffer;
  const std::ptrdiff_t shift = static_cast<std::ptrdiff_t>(window.min.y) * w + window.min.x;
  for (size_t c = 0; c < kChannels.size(); ++c) {
    const ProbeChannel& channel = kChannels[c];
    header.channels().insert(channel.name, Imf::Channel(channel.type));
    std::vector<float> values(static_cast<size_t>(w) * h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) values[static_cast<size_t>(y) * w + x] = Value(c, x, y, w, noise);
    if (channel.type == Imf::HALF) {
      auto& v = halves.emplace_back(values.begin(), values.end());
      buffer.insert(channel.name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(v.data() - shift), sizeof(Imath::half),
                                             w * sizeof(Imath::half)));
    } else if (channel.type == Imf::UINT) {
      auto& v = uints.emplace_back(values.size());
      for (size_t i = 0; i < values.size(); ++i) v[i] = std::isfinite(values[i]) ? unsigned(std::abs(values[i])) : 7u;
      buffer.insert(channel.name, Imf::Slice(Imf::UINT, reinterpret_cast<char*>(v.data() - shift), sizeof(unsigned),
                                             w * sizeof(unsigned)));
    } else {
      auto& v = floats.emplace_back(std::move(values));
      buffer.insert(channel.name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(v.data() - shift), sizeof(float),
                                             w * sizeof(float)));
    }
  }
  if (storage == Storage::kScanlines) {
    Imf::OutputFile out(file.c_str(), header);
    out.setFrameBuffer(buffer);
    out.writePixels(h);
    return;
  }
  header.setTileDescription(Imf::TileDescription(16, 8, Imf::ONE_LEVEL));
  Imf::TiledOutputFile out(file.c_str(), header);
  out.setFrameBuffer(buffer);
  out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
}

using Planes = std::vector<std::vector<float>>;

Planes ReadByShimmer(const std::filesystem::path& file, ExrZipInflater inflater, int w, int h) {
  Planes planes(kChannels.size(), std::vector<float>(static_cast<size_t>(w) * h, 12345.0f));
  auto in = ExrInput::Open(file, true);
  EXPECT_TRUE(in) << in.error();
  if (!in) return {};
  std::vector<ExrPlaneRequest> requests;
  for (size_t c = 0; c < kChannels.size(); ++c) requests.push_back({kChannels[c].name, planes[c].data()});
  Status read = in->Read(0, requests, inflater);
  EXPECT_TRUE(read) << read.error();
  return planes;
}

Planes ReadByImf(const std::filesystem::path& file, int w, int h) {
  Planes planes(kChannels.size(), std::vector<float>(static_cast<size_t>(w) * h));
  Imf::InputFile in(file.c_str());
  const Imath::Box2i window = in.header().dataWindow();
  const std::ptrdiff_t shift = static_cast<std::ptrdiff_t>(window.min.y) * w + window.min.x;
  Imf::FrameBuffer buffer;
  for (size_t c = 0; c < kChannels.size(); ++c)
    buffer.insert(kChannels[c].name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[c].data() - shift),
                                                sizeof(float), w * sizeof(float)));
  in.setFrameBuffer(buffer);
  in.readPixels(window.min.y, window.max.y);
  return planes;
}

// Bit patterns, so that NaN equals NaN and -0 differs from +0.
bool SameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(ExrZip, LibdeflateGivesOpenExrsPixelsBitForBit) {
  testing::TempDir dir;
  // Odd sizes: partial 16-line ZIP blocks and partial tiles, byte counts that
  // are no multiple of the 16- and 32-byte steps of the reconstruction.
  const std::vector<std::pair<int, int>> sizes = {{1, 1}, {3, 2}, {37, 23}, {101, 17}, {257, 40}};
  for (Imf::Compression compression : {Imf::ZIPS_COMPRESSION, Imf::ZIP_COMPRESSION})
    for (Storage storage : {Storage::kScanlines, Storage::kTiles})
      for (const auto& [w, h] : sizes) {
        SCOPED_TRACE((compression == Imf::ZIP_COMPRESSION ? "ZIP " : "ZIPS ") + std::to_string(w) + "x" +
                     std::to_string(h) + (storage == Storage::kTiles ? " tiled" : " scanlines"));
        const auto file = dir / "probe.exr";
        WriteProbe(file, w, h, compression, storage);
        const Planes fast = ReadByShimmer(file, ExrZipInflater::kLibdeflate, w, h);
        const Planes zlib = ReadByShimmer(file, ExrZipInflater::kOpenExr, w, h);
        const Planes imf = ReadByImf(file, w, h);
        ASSERT_EQ(fast.size(), kChannels.size());
        for (size_t c = 0; c < kChannels.size(); ++c) {
          EXPECT_TRUE(SameBits(fast[c], zlib[c])) << kChannels[c].name;
          EXPECT_TRUE(SameBits(fast[c], imf[c])) << kChannels[c].name;
        }
        std::filesystem::remove(file);
      }
}

// Only some channels asked for: the others still pass through the chunk.
TEST(ExrZip, ASubsetOfChannelsReadsTheSame) {
  testing::TempDir dir;
  const int w = 64, h = 33;
  const auto file = dir / "probe.exr";
  WriteProbe(file, w, h, Imf::ZIP_COMPRESSION, Storage::kScanlines);
  const Planes all = ReadByImf(file, w, h);
  auto in = ExrInput::Open(file, true);
  ASSERT_TRUE(in) << in.error();
  std::vector<float> plane(static_cast<size_t>(w) * h);
  ASSERT_TRUE(in->Read(0, {{"specular.R", plane.data()}}));
  EXPECT_TRUE(SameBits(plane, all[3]));
}

// One flipped run of bytes inside a chunk's zlib stream: the read fails with
// one line that names the file and the chunk, and prints nothing.
TEST(ExrZip, ACorruptZlibStreamIsOneErrorNamingTheFile) {
  testing::TempDir dir;
  const int w = 200, h = 64;
  const auto file = dir / "broken.exr";
  WriteProbe(file, w, h, Imf::ZIP_COMPRESSION, Storage::kScanlines);
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  // Past the header and offset table, inside the second of four chunks.
  for (size_t i = bytes.size() * 3 / 8; i < bytes.size() * 3 / 8 + 64; ++i) bytes[i] = static_cast<char>(~bytes[i]);
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;

  for (ExrZipInflater inflater : {ExrZipInflater::kLibdeflate, ExrZipInflater::kOpenExr}) {
    auto in = ExrInput::Open(file, true);
    ASSERT_TRUE(in) << in.error();  // the header is intact
    std::vector<float> plane(static_cast<size_t>(w) * h);
    ::testing::internal::CaptureStderr();
    Status read = in->Read(0, {{"specular.R", plane.data()}}, inflater);
    EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
    ASSERT_FALSE(read);
    EXPECT_EQ(read.error().rfind(file.string() + ": not a readable EXR file (", 0), 0u) << read.error();
    EXPECT_EQ(read.error().find('\n'), std::string::npos) << read.error();
    if (inflater == ExrZipInflater::kLibdeflate) {
      EXPECT_NE(read.error().find("ZIP chunk at scanline"), std::string::npos) << read.error();
    }
  }
}

}  // namespace
}  // namespace shimmer
