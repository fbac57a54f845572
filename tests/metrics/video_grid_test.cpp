// The grid video: as many tiles as sequences (and the reference's), labels
// drawn, frames x slow frames in the MP4, and its first frame showing the
// input frames where the layout puts them.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "cli_run.h"
#include "shimmer/metrics/video_grid.h"
#include "test_sequences.h"

namespace shimmer::metrics {
namespace {

using testing::Layout;
using testing::SequenceSpec;
using testing::TempDir;

constexpr int kSize = 48, kFrames = 5;

// A bright spot of its own per sequence, moving over time.
void Write(const std::filesystem::path& dir, int seed) {
  SequenceSpec s;
  s.frames = kFrames, s.width = kSize, s.height = kSize;
  s.layout = Layout::kSpecularLayer;
  s.value = [seed](int t, int x, int y) {
    const int cx = 8 + 10 * seed + t, cy = 24;
    return (x - cx) * (x - cx) + (y - cy) * (y - cy) < 16 ? 4.0f : 0.02f * float(seed + 1);
  };
  WriteSequence(dir, s);
}

// Mean absolute difference of two BGR images, per channel value.
double MeanAbsDiff(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  const cv::Scalar m = cv::mean(d);
  return (m[0] + m[1] + m[2]) / 3;
}

TEST(VideoGrid, LaysOutUpToNineTilesInRowsOfThree) {
  const GridLayout one = LayoutGrid(2, 48, 32);
  EXPECT_EQ(one.scale, 4);  // 192 / 48
  ASSERT_EQ(one.tiles.size(), 2u);
  EXPECT_EQ(one.tiles[0].image.size(), cv::Size(192, 128));
  EXPECT_EQ(one.tiles[1].image.x, one.tiles[0].image.x + 192 + 4);
  const GridLayout nine = LayoutGrid(9, 48, 32);
  EXPECT_EQ(nine.tiles[3].image.x, 0);  // the fourth starts the second row
  EXPECT_GT(nine.tiles[3].label.y, nine.tiles[0].panel.y);
  EXPECT_EQ(nine.frame.width % 2, 0);
  EXPECT_EQ(nine.frame.height % 2, 0);
  for (const GridTile& t : nine.tiles) {
    EXPECT_LE(t.panel.br().x, nine.frame.width);
    EXPECT_LE(t.panel.br().y, nine.frame.height);
  }
}

TEST(VideoGrid, WritesTheTilesLabelsAndFramesAskedFor) {
  TempDir dir;
  for (int i = 0; i < 3; ++i) Write(dir.path() / ("s" + std::to_string(i)), i);
  Write(dir.path() / "ref", 3);
  GridSequences in;
  in.tests = {dir.path() / "s0", dir.path() / "s1", dir.path() / "s2"};
  in.labels = {"none", "tk19", "k16-beckmann-rect fp_max=0.25"};
  in.reference = dir.path() / "ref";
  in.slow = 3;
  const std::filesystem::path file = dir.path() / "grid.mp4";
  auto written = WriteGridVideo(in, file);
  ASSERT_TRUE(written) << written.error();
  EXPECT_EQ(written->tiles, 4);
  EXPECT_EQ(written->frames, kFrames * 3);

  cv::VideoCapture capture(file.string(), cv::CAP_FFMPEG);
  ASSERT_TRUE(capture.isOpened());
  const GridLayout layout = LayoutGrid(4, kSize, kSize);
  EXPECT_EQ(int(capture.get(cv::CAP_PROP_FRAME_WIDTH)), layout.frame.width);
  EXPECT_EQ(int(capture.get(cv::CAP_PROP_FRAME_HEIGHT)), layout.frame.height);
  std::vector<cv::Mat> decoded;
  for (cv::Mat f; capture.read(f);) decoded.push_back(f.clone());
  ASSERT_EQ(int(decoded.size()), kFrames * 3);
  if (const char* keep = std::getenv("SHIMMER_KEEP_GRID_FRAME")) cv::imwrite(keep, decoded[0]);

  // The first frame's tiles are the inputs' first frames, enlarged: tile 0
  // the reference, then the tests in label order (lossy codec: a tolerance).
  const std::vector<std::filesystem::path> inputs = {in.reference, in.tests[0], in.tests[1], in.tests[2]};
  for (int tile = 0; tile < 4; ++tile) {
    auto seq = OpenSequence(inputs[tile], {});
    ASSERT_TRUE(seq) << seq.error();
    auto frame = ReadFrame(seq->frames[0], seq->layer, kSize, kSize, false);
    ASSERT_TRUE(frame) << frame.error();
    cv::Mat expected;
    cv::resize(DisplayGrey(frame->luminance), expected, layout.tiles[tile].image.size(), 0, 0, cv::INTER_NEAREST);
    const cv::Mat got = decoded[0](layout.tiles[tile].image);
    EXPECT_LT(MeanAbsDiff(got, expected), 4.0) << "tile " << tile;
    // Another tile's content would not match: the spots lie elsewhere.
    if (tile > 0) {
      const cv::Mat other = decoded[0](layout.tiles[tile == 3 ? 1 : tile + 1].image);
      EXPECT_GT(MeanAbsDiff(other, expected), 2 * MeanAbsDiff(got, expected)) << "tile " << tile;
    }
    // Each label bar has text drawn in it (white on dark grey).
    cv::Mat bar;
    cv::cvtColor(decoded[0](layout.tiles[tile].label), bar, cv::COLOR_BGR2GRAY);
    EXPECT_GT(cv::countNonZero(bar > 200), 20) << "tile " << tile;
  }
  // Slow motion repeats frames: frames 0..2 are one input frame, 3 the next.
  EXPECT_LT(MeanAbsDiff(decoded[0], decoded[2]), 1.0);
  EXPECT_GT(MeanAbsDiff(decoded[2](layout.tiles[1].image), decoded[3](layout.tiles[1].image)), 0.5);
  // The legend (below the reference) and the test errors are colour, not grey.
  cv::Mat hsv;
  cv::cvtColor(decoded[0](layout.tiles[1].panel), hsv, cv::COLOR_BGR2HSV);
  std::vector<cv::Mat> channels;
  cv::split(hsv, channels);
  EXPECT_GT(cv::countNonZero(channels[1] > 80), 10);  // saturated: the spots' signed error
}

TEST(VideoGrid, RefusesWhatItCannotShow) {
  TempDir dir;
  Write(dir.path() / "a", 0);
  SequenceSpec small;
  small.frames = kFrames, small.width = 16, small.height = 16;
  small.value = [](int, int, int) { return 0.5f; };
  WriteSequence(dir.path() / "small", small);
  GridSequences in;
  in.tests = {dir.path() / "a", dir.path() / "small"};
  auto mismatch = WriteGridVideo(in, dir.path() / "x.mp4");
  ASSERT_FALSE(mismatch);
  EXPECT_NE(mismatch.error().find("must be the same size"), std::string::npos) << mismatch.error();
  in.tests.assign(9, dir.path() / "a");
  in.reference = dir.path() / "a";
  auto many = WriteGridVideo(in, dir.path() / "x.mp4");
  ASSERT_FALSE(many);
  EXPECT_NE(many.error().find("at most 8 test sequences"), std::string::npos) << many.error();
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "x.mp4"));
}

TEST(VideoCli, WritesAGridOrRefusesWithOneMessage) {
  TempDir dir;
  Write(dir.path() / "a", 0);
  Write(dir.path() / "b", 1);
  Write(dir.path() / "ref", 2);
  const std::string a = (dir.path() / "a").string(), b = (dir.path() / "b").string();
  const std::string out = (dir.path() / "g.mp4").string();
  auto run = [](const std::string& args) { return shimmer::testing::RunShimmer(SHIMMER_EXE, "video " + args); };
  const auto ok = run(a + " " + b + " --reference " + (dir.path() / "ref").string() + " --slow 2 -o " + out);
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find("3 tiles, 10 frames"), std::string::npos) << ok.output;
  EXPECT_TRUE(std::filesystem::exists(out));
  struct Case {
    std::string args, message;
  };
  std::string nine;
  for (int i = 0; i < 9; ++i) nine += a + " ";
  const Case cases[] = {
      {a + " " + b + " --label one -o " + out, "--label must be given once per test sequence (2), got 1"},
      {nine + "-o " + out, "at most 8 test sequences"},
      {a + " --slow 0 -o " + out, "--slow must be 1..100"},
      {(dir.path() / "nope").string() + " -o " + out, "no such file or directory"},
      {a + " -o " + (dir.path() / "no" / "g.mp4").string(), "does not exist"},
  };
  for (const Case& c : cases) {
    const auto r = run(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.args << "\n" << r.output;
  }
}

}  // namespace
}  // namespace shimmer::metrics
