#include <gtest/gtest.h>

#include <Imath/half.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfMultiPartOutputFile.h>
#include <ImfOutputFile.h>
#include <ImfOutputPart.h>
#include <ImfPartType.h>
#include <ImfTiledOutputFile.h>

#include <fstream>

#include "shimmer/metrics/exr_sequence.h"
#include "test_sequences.h"

namespace shimmer::metrics {
namespace {

using testing::Layout;
using testing::SequenceSpec;
using testing::TempDir;
using testing::WriteExrMats;
using testing::WriteSequence;

SequenceSpec Ramp(Layout layout, int frames = 3) {
  SequenceSpec s;
  s.frames = frames;
  s.width = 8;
  s.height = 6;
  s.layout = layout;
  s.value = [](int t, int x, int y) { return 0.25f * t + 0.125f * x + 0.5f * y; };
  return s;
}

bool Contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(ExrSequence, ReadsPlainRgbInNameOrder) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kBeautyRgb, 12));
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_TRUE(seq) << seq.error();
  EXPECT_EQ(seq->frames.size(), 12u);
  EXPECT_EQ(seq->width, 8);
  EXPECT_EQ(seq->height, 6);
  EXPECT_EQ(seq->layer, "beauty");
  EXPECT_EQ(seq->fps, 60);
  EXPECT_EQ(seq->fps_source, "default");
  EXPECT_FALSE(seq->has_motion);
  for (size_t i = 1; i < seq->frames.size(); ++i)
    EXPECT_LT(seq->frames[i - 1].filename().string(), seq->frames[i].filename().string());
  auto frame = ReadFrame(seq->frames[11], seq->layer, 8, 6, false);
  ASSERT_TRUE(frame) << frame.error();
  EXPECT_FLOAT_EQ(frame->luminance.at<float>(5, 7), 0.25f * 11 + 0.125f * 7 + 0.5f * 5);
}

TEST(ExrSequence, LuminanceUsesRec709Weights) {
  TempDir dir;
  cv::Mat r(2, 2, CV_32F, cv::Scalar(1.0)), g(2, 2, CV_32F, cv::Scalar(2.0)), b(2, 2, CV_32F, cv::Scalar(4.0));
  ASSERT_TRUE(WriteExrMats(dir / "a.exr", {{"R", r}, {"G", g}, {"B", b}}));
  auto frame = ReadFrame(dir / "a.exr", "beauty", 2, 2, false);
  ASSERT_TRUE(frame) << frame.error();
  EXPECT_FLOAT_EQ(frame->luminance.at<float>(1, 1), static_cast<float>(0.2126 + 2 * 0.7152 + 4 * 0.0722));
}

TEST(ExrSequence, ReadsHalfRgba) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kBeautyRgbHalf));
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_TRUE(seq) << seq.error();
  auto frame = ReadFrame(seq->frames[2], seq->layer, 8, 6, false);
  ASSERT_TRUE(frame) << frame.error();
  EXPECT_FLOAT_EQ(frame->luminance.at<float>(3, 4), 0.5f + 0.5f + 1.5f);  // exact in half
}

TEST(ExrSequence, PrefersSpecularLayerAndHonoursLayerOption) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kSpecularLayer));
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_TRUE(seq) << seq.error();
  EXPECT_EQ(seq->layer, "specular");
  auto spec = ReadFrame(seq->frames[1], "specular", 8, 6, false);
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_FLOAT_EQ(spec->luminance.at<float>(0, 1), 0.25f + 0.125f);
  auto beauty = OpenSequence(dir.path(), {.layer = "beauty"});
  ASSERT_TRUE(beauty) << beauty.error();
  auto b = ReadFrame(beauty->frames[1], "beauty", 8, 6, false);
  EXPECT_FLOAT_EQ(b->luminance.at<float>(0, 1), 0.5f);
}

TEST(ExrSequence, ReadsMultiPartFilesWithOneLayerPerPart) {
  TempDir dir;
  const int w = 4, h = 3;
  std::vector<float> beauty(w * h, 0.5f), spec(w * h);
  for (int i = 0; i < w * h; ++i) spec[i] = 0.1f * i;
  std::vector<Imf::Header> headers(2, Imf::Header(w, h));
  headers[0].setName("rgba");
  headers[1].setName("specular");
  for (auto& hd : headers) {
    hd.setType(Imf::SCANLINEIMAGE);
    for (const char* c : {"R", "G", "B"}) hd.channels().insert(c, Imf::Channel(Imf::FLOAT));
  }
  {
    Imf::MultiPartOutputFile out((dir / "f0.exr").c_str(), headers.data(), 2);
    for (int p = 0; p < 2; ++p) {
      Imf::OutputPart part(out, p);
      Imf::FrameBuffer fb;
      float* data = p == 0 ? beauty.data() : spec.data();
      for (const char* c : {"R", "G", "B"})
        fb.insert(c, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(data), sizeof(float), w * sizeof(float)));
      part.setFrameBuffer(fb);
      part.writePixels(h);
    }
  }
  std::filesystem::copy_file(dir / "f0.exr", dir / "f1.exr");
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_TRUE(seq) << seq.error();
  EXPECT_EQ(seq->layer, "specular");
  auto frame = ReadFrame(seq->frames[0], "specular", w, h, false);
  ASSERT_TRUE(frame) << frame.error();
  EXPECT_FLOAT_EQ(frame->luminance.at<float>(2, 3), 0.1f * 11);
  auto b = ReadFrame(seq->frames[0], "beauty", w, h, false);
  ASSERT_TRUE(b) << b.error();
  EXPECT_FLOAT_EQ(b->luminance.at<float>(0, 0), 0.5f);
}

TEST(ExrSequence, ReadsMotionVectors) {
  TempDir dir;
  SequenceSpec s = Ramp(Layout::kBeautyRgb);
  s.motion = [](int t, int x, int) { return cv::Vec2f(-1.0f * t, 0.5f * x); };
  WriteSequence(dir.path(), s);
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_TRUE(seq) << seq.error();
  EXPECT_TRUE(seq->has_motion);
  auto frame = ReadFrame(seq->frames[2], seq->layer, 8, 6, true);
  ASSERT_TRUE(frame) << frame.error();
  EXPECT_EQ(frame->motion.at<cv::Vec2f>(1, 3), cv::Vec2f(-2.0f, 1.5f));
}

// Frames are decoded chunk by chunk in parallel through OpenEXR's core API.
// Whatever the layout (scanline blocks of 1, 16 or 32 lines, tiles, mipmapped
// tiles), the compression, a data window off the origin whose size is no
// multiple of the block, half or float channels, and channels not asked for,
// ReadFrame must give bit for bit what OpenEXR's C++ reader gives.
enum class Storage { kScanlines, kTiles, kMipmappedTiles };

void WriteLayoutProbe(const std::filesystem::path& file, Storage storage, Imf::Compression compression) {
  const Imath::Box2i window({-3, 5}, {33, 33});  // 37 x 29
  const int w = 37, h = 29;
  Imf::Header header(window, window);
  header.compression() = compression;
  std::vector<std::vector<float>> floats;
  std::vector<std::vector<Imath::half>> halves;
  Imf::FrameBuffer buffer;
  const std::vector<std::pair<std::string, bool>> channels = {
      {"R", true},           {"G", true},           {"B", true}, {"specular.R", false},
      {"specular.G", false}, {"specular.B", false}, {"Z", false}};
  for (size_t c = 0; c < channels.size(); ++c) {
    const auto& [name, half] = channels[c];
    header.channels().insert(name, Imf::Channel(half ? Imf::HALF : Imf::FLOAT));
    std::vector<float> values(w * h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) values[y * w + x] = std::sin(0.37f * x + 0.11f * y * (c + 1)) * (1.0f + 3.0f * c);
    // Shift the base so that the window's corner is element 0.
    const std::ptrdiff_t shift = static_cast<std::ptrdiff_t>(window.min.y) * w + window.min.x;
    if (half) {
      auto& v = halves.emplace_back(values.begin(), values.end());
      buffer.insert(name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(v.data() - shift), sizeof(Imath::half),
                                     w * sizeof(Imath::half)));
    } else {
      auto& v = floats.emplace_back(std::move(values));
      buffer.insert(
          name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(v.data() - shift), sizeof(float), w * sizeof(float)));
    }
  }
  if (storage == Storage::kScanlines) {
    Imf::OutputFile out(file.c_str(), header);
    out.setFrameBuffer(buffer);
    out.writePixels(h);
    return;
  }
  header.setTileDescription(
      Imf::TileDescription(16, 8, storage == Storage::kTiles ? Imf::ONE_LEVEL : Imf::MIPMAP_LEVELS));
  Imf::TiledOutputFile out(file.c_str(), header);
  out.setFrameBuffer(buffer);  // coarser levels reuse the base pixels: only level 0 is read
  for (int level = 0; level < out.numLevels(); ++level)
    out.writeTiles(0, out.numXTiles(level) - 1, 0, out.numYTiles(level) - 1, level);
}

cv::Mat LuminanceByImf(const std::filesystem::path& file, const std::string& prefix) {
  Imf::InputFile in(file.c_str());
  const Imath::Box2i window = in.header().dataWindow();
  const int w = window.max.x - window.min.x + 1, h = window.max.y - window.min.y + 1;
  std::vector<cv::Mat> rgb(3, cv::Mat(h, w, CV_32F));
  Imf::FrameBuffer buffer;
  for (int c = 0; c < 3; ++c) {
    rgb[c] = cv::Mat(h, w, CV_32F);
    char* base = reinterpret_cast<char*>(rgb[c].ptr<float>() - (window.min.y * w + window.min.x));
    buffer.insert(prefix + "RGB"[c], Imf::Slice(Imf::FLOAT, base, sizeof(float), w * sizeof(float)));
  }
  in.setFrameBuffer(buffer);
  in.readPixels(window.min.y, window.max.y);
  cv::Mat y(h, w, CV_32F);
  for (int i = 0; i < w * h; ++i)
    y.ptr<float>()[i] = static_cast<float>(kLumaR * rgb[0].ptr<float>()[i] + kLumaG * rgb[1].ptr<float>()[i] +
                                           kLumaB * rgb[2].ptr<float>()[i]);
  return y;
}

TEST(ExrSequence, ReadsEveryStorageAndCompressionAsOpenExrDoes) {
  TempDir dir;
  const Imf::Compression compressions[] = {Imf::NO_COMPRESSION,  Imf::RLE_COMPRESSION,  Imf::ZIPS_COMPRESSION,
                                           Imf::ZIP_COMPRESSION, Imf::PIZ_COMPRESSION,  Imf::PXR24_COMPRESSION,
                                           Imf::B44_COMPRESSION, Imf::B44A_COMPRESSION, Imf::DWAA_COMPRESSION,
                                           Imf::DWAB_COMPRESSION};
  for (Storage storage : {Storage::kScanlines, Storage::kTiles, Storage::kMipmappedTiles})
    for (Imf::Compression compression : compressions) {
      SCOPED_TRACE("storage " + std::to_string(static_cast<int>(storage)) + ", compression " +
                   std::to_string(static_cast<int>(compression)));
      const auto file = dir / "probe.exr";
      WriteLayoutProbe(file, storage, compression);
      for (const std::string layer : {"specular", "beauty"}) {
        auto frame = ReadFrame(file, layer, 37, 29, false);
        ASSERT_TRUE(frame) << frame.error();
        const cv::Mat expected = LuminanceByImf(file, layer == "beauty" ? "" : layer + ".");
        EXPECT_EQ(cv::countNonZero(frame->luminance != expected), 0) << layer;
      }
      // The oracle itself reads the written values where the codec is lossless.
      if (compression <= Imf::PIZ_COMPRESSION) {
        const float r = std::sin(0.37f * 5 + 0.11f * 7 * 4) * 10.0f, g = std::sin(0.37f * 5 + 0.11f * 7 * 5) * 13.0f,
                    b = std::sin(0.37f * 5 + 0.11f * 7 * 6) * 16.0f;
        EXPECT_EQ(LuminanceByImf(file, "specular.").at<float>(7, 5),
                  static_cast<float>(kLumaR * r + kLumaG * g + kLumaB * b));
      }
      std::filesystem::remove(file);
    }
}

TEST(ExrSequence, SequenceJsonGivesFpsAndFrameList) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kBeautyRgb, 4));
  std::ofstream(dir / "sequence.json") << R"({"fps": 24, "frames": ["frame_0002.exr", "frame_0000.exr"]})";
  auto seq = OpenSequence(dir / "sequence.json", {.fps = 30.0});
  ASSERT_TRUE(seq) << seq.error();
  EXPECT_EQ(seq->fps, 24);
  EXPECT_EQ(seq->fps_source, "sequence.json");
  ASSERT_EQ(seq->frames.size(), 2u);
  EXPECT_EQ(seq->frames[0].filename(), "frame_0002.exr");
  EXPECT_EQ(seq->warnings.size(), 1u);  // --fps disagreed
  // The directory form reads the same sidecar for its fps.
  auto by_dir = OpenSequence(dir.path(), {});
  ASSERT_TRUE(by_dir) << by_dir.error();
  EXPECT_EQ(by_dir->fps, 24);
  EXPECT_EQ(by_dir->frames.size(), 4u);
}

// The shape shimmer's renderer writes: one object per frame.
TEST(ExrSequence, SequenceJsonFramesMayBeObjectsWithAFile) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kBeautyRgb, 3));
  std::ofstream(dir / "sequence.json")
      << R"({"fps": 30, "frames": [{"file": "frame_0000.exr", "gpu_ms": 1.5, "time_s": 0},
                                   {"file": "frame_0001.exr", "gpu_ms": 1.4, "time_s": 0.033}]})";
  auto seq = OpenSequence(dir / "sequence.json", {});
  ASSERT_TRUE(seq) << seq.error();
  ASSERT_EQ(seq->frames.size(), 2u);
  EXPECT_EQ(seq->frames[1].filename(), "frame_0001.exr");
  std::ofstream(dir / "sequence.json") << R"({"frames": [{"gpu_ms": 1.5}]})";
  auto bad = OpenSequence(dir / "sequence.json", {});
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().find("\"frames\" must be an array of file names"), std::string::npos) << bad.error();
}

TEST(ExrSequence, FpsOptionWhenNoSidecar) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kBeautyRgb, 2));
  auto seq = OpenSequence(dir.path(), {.fps = 90.0});
  ASSERT_TRUE(seq);
  EXPECT_EQ(seq->fps, 90);
  EXPECT_EQ(seq->fps_source, "--fps");
}

TEST(ExrSequenceErrors, EmptyDirectory) {
  TempDir dir;
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_FALSE(seq);
  EXPECT_TRUE(Contains(seq.error(), dir.path().string()));
  EXPECT_TRUE(Contains(seq.error(), "no .exr frames"));
}

TEST(ExrSequenceErrors, MissingPath) {
  auto seq = OpenSequence("/nonexistent/shimmer/frames", {});
  ASSERT_FALSE(seq);
  EXPECT_TRUE(Contains(seq.error(), "no such file or directory"));
}

TEST(ExrSequenceErrors, DifferentFrameSizesNameTheFrame) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kBeautyRgb, 3));
  SequenceSpec other = Ramp(Layout::kBeautyRgb, 1);
  other.width = 9;
  other.prefix = "frame_0001b";
  WriteSequence(dir.path(), other);
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_FALSE(seq);
  EXPECT_TRUE(Contains(seq.error(), "frame_0001b0000.exr")) << seq.error();
  EXPECT_TRUE(Contains(seq.error(), "9x6")) << seq.error();
}

TEST(ExrSequenceErrors, MissingLayerNamesFileAndLayers) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kBeautyRgb, 2));
  auto seq = OpenSequence(dir.path(), {.layer = "specular"});
  ASSERT_FALSE(seq);
  EXPECT_TRUE(Contains(seq.error(), "frame_0000.exr")) << seq.error();
  EXPECT_TRUE(Contains(seq.error(), "no layer 'specular'")) << seq.error();
  EXPECT_TRUE(Contains(seq.error(), "beauty")) << seq.error();
}

TEST(ExrSequenceErrors, MissingChannelInALaterFrame) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kSpecularLayer, 2));
  cv::Mat v(6, 8, CV_32F, cv::Scalar(1));
  ASSERT_TRUE(
      WriteExrMats(dir / "frame_0002.exr", {{"R", v}, {"G", v}, {"B", v}, {"specular.R", v}, {"specular.B", v}}));
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_FALSE(seq);
  EXPECT_TRUE(Contains(seq.error(), "frame_0002.exr")) << seq.error();
  EXPECT_TRUE(Contains(seq.error(), "lacks channel")) << seq.error();
}

TEST(ExrSequenceErrors, NonExrFile) {
  TempDir dir;
  WriteSequence(dir.path(), Ramp(Layout::kBeautyRgb, 2));
  std::ofstream(dir / "frame_0002.exr") << "this is not an EXR file";
  auto seq = OpenSequence(dir.path(), {});
  ASSERT_FALSE(seq);
  EXPECT_TRUE(Contains(seq.error(), "frame_0002.exr")) << seq.error();
  EXPECT_TRUE(Contains(seq.error(), "not a readable EXR")) << seq.error();
}

TEST(ExrSequenceErrors, TruncatedFileFailsOnRead) {
  TempDir dir;
  SequenceSpec s = Ramp(Layout::kBeautyRgb, 1);
  s.width = 64, s.height = 64;
  WriteSequence(dir.path(), s);
  const auto file = dir / "frame_0000.exr";
  std::filesystem::resize_file(file, std::filesystem::file_size(file) * 2 / 3);
  auto seq = OpenSequence(dir.path(), {});  // the header alone is intact
  Result<LuminanceFrame> frame =
      seq ? ReadFrame(file, "beauty", 64, 64, false) : Result<LuminanceFrame>::Failure(seq.error());
  ASSERT_FALSE(frame);
  EXPECT_TRUE(Contains(frame.error(), "frame_0000.exr")) << frame.error();
}

TEST(ReadMask, AnyImageNonzeroIsIn) {
  TempDir dir;
  cv::Mat m = cv::Mat::zeros(6, 8, CV_32F);
  m.at<float>(2, 3) = 0.5f;
  m.at<float>(4, 1) = std::numeric_limits<float>::quiet_NaN();
  ASSERT_TRUE(WriteExrMats(dir / "m.exr", {{"Y", m}}));
  auto mask = ReadMask(dir / "m.exr", 8, 6);
  ASSERT_TRUE(mask) << mask.error();
  EXPECT_EQ(cv::countNonZero(*mask), 1);
  EXPECT_EQ(mask->at<uint8_t>(2, 3), 1);
  auto wrong = ReadMask(dir / "m.exr", 9, 6);
  ASSERT_FALSE(wrong);
  EXPECT_TRUE(Contains(wrong.error(), "8x6")) << wrong.error();
}

}  // namespace
}  // namespace shimmer::metrics
