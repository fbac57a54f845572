// `shimmer metrics` end to end: runs the built executable on generated
// sequences and checks exit codes, messages, JSON and written files.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "shimmer/metrics/exr_sequence.h"
#include "test_sequences.h"

namespace shimmer::metrics {
namespace {

using testing::SequenceSpec;
using testing::TempDir;
using testing::WriteSequence;

struct Outcome {
  int exit_code = -1;
  std::string out, err;
};

Outcome RunShimmer(const std::string& args, const std::filesystem::path& scratch) {
  const auto err_file = scratch / "stderr.txt";
  const std::string command = std::string(SHIMMER_EXE) + " metrics " + args + " 2>" + err_file.string();
  Outcome o;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return o;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) o.out.append(buffer.data(), n);
  const int status = pclose(pipe);
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err_file);
  o.err.assign(std::istreambuf_iterator<char>(in), {});
  return o;
}

SequenceSpec Flicker(int frames) {
  SequenceSpec s;
  s.frames = frames;
  s.width = s.height = 24;
  s.layout = testing::Layout::kSpecularLayer;
  s.value = [](int t, int x, int y) { return (x == 12 && y == 12 ? 4.0f : 0.3f) + 0.05f * ((t + x) % 3); };
  return s;
}

SequenceSpec Steady(int frames) {
  SequenceSpec s = Flicker(frames);
  s.value = [](int, int x, int y) { return x == 12 && y == 12 ? 4.0f : 0.3f; };
  return s;
}

TEST(MetricsCli, JsonHasTheDocumentedKeys) {
  TempDir dir;
  WriteSequence(dir / "test", Flicker(12));
  WriteSequence(dir / "ref", Steady(12));
  Outcome o = RunShimmer((dir / "test").string() + " " + (dir / "ref").string() + " --json --fps 30", dir.path());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  nlohmann::json j = nlohmann::json::parse(o.out);
  for (const char* key : {"frames", "width", "height", "pixels", "fps", "tv_test", "tv_ref", "tv_err", "tv_ratio",
                          "energy_bias", "temporal_diff_err", "rmse", "relmse", "nan_pixels", "flicker"})
    EXPECT_TRUE(j.contains(key)) << key;
  for (const char* key : {"freq_hz", "psd", "segment_length", "bands", "flicker_index"})
    EXPECT_TRUE(j["flicker"].contains(key)) << key;
  EXPECT_EQ(j["frames"], 12);
  EXPECT_EQ(j["fps"], 30.0);
  EXPECT_EQ(j["layer"], "specular");
  EXPECT_EQ(j["flicker"]["segment_length"], 12);
  EXPECT_EQ(j["flicker"]["freq_hz"].size(), j["flicker"]["psd"].size());
  EXPECT_GT(j["tv_err"].get<double>(), 0.0);
  EXPECT_TRUE(j["tv_ratio"].is_null());  // steady reference: undefined ratio, reported as null
}

TEST(MetricsCli, WithoutReferenceOnlyReferenceFreeKeys) {
  TempDir dir;
  SequenceSpec s = Flicker(6);
  s.motion = [](int, int, int) { return cv::Vec2f(0, 0); };
  WriteSequence(dir / "test", s);
  Outcome o = RunShimmer((dir / "test").string() + " --json", dir.path());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  nlohmann::json j = nlohmann::json::parse(o.out);
  EXPECT_FALSE(j.contains("tv_ref"));
  EXPECT_FALSE(j.contains("energy_bias"));
  EXPECT_TRUE(j.contains("warp_err"));
  EXPECT_EQ(j["flicker"]["signal"], "test");
}

TEST(MetricsCli, OutWritesMapsHeatmapsAndSpectrum) {
  TempDir dir;
  WriteSequence(dir / "test", Flicker(8));
  WriteSequence(dir / "ref", Steady(8));
  Outcome o = RunShimmer((dir / "test").string() + " " + (dir / "ref").string() + " --out " + (dir / "out").string(),
                         dir.path());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_NE(o.out.find("tv_err"), std::string::npos);
  for (const char* f : {"tv_test.exr", "tv_ref.exr", "tv_err.exr", "energy_bias.exr", "tv_test.png", "tv_err.png",
                        "energy_bias.png", "spectrum.csv", "spectrum.gp", "metrics.json"})
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / f)) << f;
  auto tv = ReadFrame(dir / "out" / "tv_err.exr", "beauty", 24, 24, false);
  ASSERT_TRUE(tv) << tv.error();
  EXPECT_GT(tv->luminance.at<float>(5, 5), 0.0f);
  // No partial files left behind.
  for (const auto& e : std::filesystem::directory_iterator(dir / "out"))
    EXPECT_EQ(e.path().filename().string().find(".partial"), std::string::npos) << e.path();
}

// --out is all or nothing: a second run that fails part-way (here a
// file-size limit, as a full disk would) leaves the first run's files as
// they were, and nothing of its own.
TEST(MetricsCli, FailedOutLeavesThePreviousOutputsWhole) {
  TempDir dir;
  WriteSequence(dir / "test", Flicker(8));
  WriteSequence(dir / "ref", Steady(8));
  const std::string args = (dir / "test").string() + " " + (dir / "ref").string() + " --out " + (dir / "out").string();
  ASSERT_EQ(RunShimmer(args, dir.path()).exit_code, 0);
  auto listing = [&] {
    std::map<std::string, std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(dir / "out")) {
      std::ifstream in(e.path(), std::ios::binary);
      files[e.path().filename().string()].assign(std::istreambuf_iterator<char>(in), {});
    }
    return files;
  };
  const auto before = listing();
  // Another sequence, so that every map would change.
  WriteSequence(dir / "test", Steady(8));
  const std::string limited = "sh -c 'ulimit -f 8; exec " + std::string(SHIMMER_EXE) + " metrics " + args + "' 2>" +
                              (dir / "stderr.txt").string();
  const int status = std::system(limited.c_str());
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 1);
  EXPECT_EQ(listing(), before);
}

TEST(MetricsCli, VideoIsWrittenOrClearlyRefused) {
  TempDir dir;
  WriteSequence(dir / "test", Flicker(6));
  WriteSequence(dir / "ref", Steady(6));
  Outcome o =
      RunShimmer((dir / "test").string() + " " + (dir / "ref").string() + " --video " + (dir / "flicker.mp4").string(),
                 dir.path());
  if (o.exit_code == 0) {
    ASSERT_TRUE(std::filesystem::exists(dir / "flicker.mp4"));
    EXPECT_GT(std::filesystem::file_size(dir / "flicker.mp4"), 0u);
  } else {
    EXPECT_EQ(o.exit_code, 2);
    EXPECT_NE(o.err.find("cannot encode MP4"), std::string::npos) << o.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "flicker.mp4"));
  }
}

struct BadInputCase {
  const char* name;
  std::function<std::string(const TempDir&)> setup;  // returns the arguments
  const char* message;                               // part of the one error line
};

TEST(MetricsCli, BadInputExitsTwoWithOneClearMessage) {
  const std::vector<BadInputCase> cases = {
      {"empty directory",
       [](const TempDir& d) {
         std::filesystem::create_directories(d / "empty");
         return (d / "empty").string();
       },
       "no .exr frames"},
      {"different lengths",
       [](const TempDir& d) {
         WriteSequence(d / "t", Steady(4));
         WriteSequence(d / "r", Steady(3));
         return (d / "t").string() + " " + (d / "r").string();
       },
       "has 4 frames but REF"},
      {"different sizes",
       [](const TempDir& d) {
         WriteSequence(d / "t", Steady(3));
         SequenceSpec s = Steady(3);
         s.width = 20;
         WriteSequence(d / "r", s);
         return (d / "t").string() + " " + (d / "r").string();
       },
       "is 24x24 but REF"},
      {"missing layer",
       [](const TempDir& d) {
         WriteSequence(d / "t", Steady(3));
         return (d / "t").string() + " --layer diffuse";
       },
       "no layer 'diffuse'"},
      {"non-EXR file",
       [](const TempDir& d) {
         WriteSequence(d / "t", Steady(3));
         std::ofstream(d / "t" / "frame_0001.exr") << "garbage";
         return (d / "t").string();
       },
       "frame_0001.exr: not a readable EXR"},
      {"truncated file",
       [](const TempDir& d) {
         SequenceSpec s = Steady(3);
         s.width = s.height = 96;
         WriteSequence(d / "t", s);
         std::filesystem::resize_file(d / "t" / "frame_0002.exr",
                                      std::filesystem::file_size(d / "t" / "frame_0002.exr") / 2);
         return (d / "t").string();
       },
       "frame_0002.exr"},
      {"bad signal",
       [](const TempDir& d) {
         WriteSequence(d / "t", Steady(3));
         return (d / "t").string() + " --signal error";
       },
       "--signal error needs a reference"},
  };
  for (const BadInputCase& c : cases) {
    TempDir dir;
    Outcome o = RunShimmer(c.setup(dir), dir.path());
    EXPECT_EQ(o.exit_code, 2) << c.name << ": " << o.err;
    EXPECT_EQ(o.err.rfind("shimmer: error: ", 0), 0u) << c.name << ": " << o.err;
    EXPECT_NE(o.err.find(c.message), std::string::npos) << c.name << ": " << o.err;
    EXPECT_TRUE(o.out.empty()) << c.name;
  }
}

TEST(MetricsCli, NanPixelsWarnButSucceed) {
  TempDir dir;
  SequenceSpec s = Steady(4);
  s.value = [](int t, int x, int y) {
    return x == 1 && y == 1 && t == 2 ? std::numeric_limits<float>::quiet_NaN() : 0.5f;
  };
  WriteSequence(dir / "t", s);
  Outcome o = RunShimmer((dir / "t").string() + " --json", dir.path());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  nlohmann::json j = nlohmann::json::parse(o.out);
  EXPECT_EQ(j["nan_pixels"], 1);
  EXPECT_EQ(j["tv_test"], 0.0);
  EXPECT_NE(o.err.find("frame_0002.exr"), std::string::npos) << o.err;
}

// --sparkle-threshold adds the "sparkles" object (and the text lines); without it, neither.
TEST(MetricsCli, SparkleThresholdAddsSparkleStatistics) {
  TempDir dir;
  WriteSequence(dir / "test", Flicker(6));  // one 4.0 pixel a frame, everything else below 0.5
  WriteSequence(dir / "ref", Steady(6));
  const std::string sequences = (dir / "test").string() + " " + (dir / "ref").string();
  Outcome o = RunShimmer(sequences + " --json --sparkle-threshold 2", dir.path());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  nlohmann::json j = nlohmann::json::parse(o.out);
  ASSERT_TRUE(j.contains("sparkles"));
  EXPECT_EQ(j["sparkles"]["threshold"], 2.0);
  EXPECT_EQ(j["sparkles"]["test"]["mean_count"], 1.0);
  EXPECT_EQ(j["sparkles"]["test"]["count_variance"], 0.0);
  EXPECT_EQ(j["sparkles"]["reference"]["mean_count"], 1.0);
  EXPECT_EQ(j["sparkles"]["mean_count_ratio"], 1.0);
  EXPECT_TRUE(j["sparkles"]["count_variance_ratio"].is_null());  // a steady reference: 0 variance
  // No motion anywhere: tracked in place, with a warning.
  EXPECT_EQ(j["sparkles"]["test"]["motion"], "none");
  EXPECT_NE(o.err.find("neither TEST nor REF has motion.X/Y"), std::string::npos) << o.err;

  Outcome plain = RunShimmer(sequences + " --json", dir.path());
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_FALSE(nlohmann::json::parse(plain.out).contains("sparkles"));

  Outcome text = RunShimmer(sequences + " --sparkle-threshold 2", dir.path());
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("sparkles > 2 in test: 1 px per frame"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("sparkles > 2 in reference:"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("sparkles test/reference: mean count 1,"), std::string::npos) << text.out;
  EXPECT_EQ(RunShimmer(sequences, dir.path()).out.find("sparkles"), std::string::npos);
}

TEST(MetricsCli, BadSparkleThresholdIsOneError) {
  TempDir dir;
  WriteSequence(dir / "test", Steady(3));
  for (const char* value : {"-1", "-0.5", "nan", "inf", "-inf"}) {
    Outcome o = RunShimmer((dir / "test").string() + " --json --sparkle-threshold " + value, dir.path());
    EXPECT_EQ(o.exit_code, 2) << value << ": " << o.err;
    EXPECT_EQ(o.err.rfind("shimmer: error: --sparkle-threshold must be a finite number >= 0", 0), 0u)
        << value << ": " << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << value << ": " << o.err;
    EXPECT_TRUE(o.out.empty()) << value;
  }
}

}  // namespace
}  // namespace shimmer::metrics
