// The `shimmer metrics` pass and its parts, side by side in one run, on
// synthetic renderer-like sequences: float EXR, ZIP, beauty + specular +
// motion layers (8 channels).
//
//   BM_MetricsPass     the whole pass, as `shimmer metrics TEST REF` runs it
//   BM_DecodeOnly      only reading the channels the pass reads, every frame
//                      pair; ZIP chunks inflated by libdeflate or by
//                      OpenEXR's zlib path (ExrZipInflater)
//   BM_Arithmetic      only MetricsAccumulator on frames already in memory:
//                      AddFrame per pair (finish:0), or its whole life
//                      (finish:1): construction (zeroing the per-pixel sums),
//                      every AddFrame and Finish (the bootstrap)
//   BM_Bootstrap       only the intervals' block bootstrap (1000 replicates
//                      over the 8x8 tiles of a frame and its frame blocks)
//   BM_NumpyBaseline   bench/metrics_numpy_baseline.py on the same files, in
//                      the same run; its own clock (reading included,
//                      interpreter start and imports excluded)
//
// The sequences are written once into $SHIMMER_BENCH_DIR (kept) or into a
// temporary directory that is removed at exit.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "shimmer/core/exr_input.h"
#include "shimmer/metrics/block_bootstrap.h"
#include "shimmer/metrics/exr_sequence.h"
#include "shimmer/metrics/metrics_accumulator.h"
#include "shimmer/metrics/metrics_report.h"

namespace fs = std::filesystem;
namespace m = shimmer::metrics;

namespace {

struct BenchDir {
  fs::path path;
  bool keep = false;
  BenchDir() {
    if (const char* d = std::getenv("SHIMMER_BENCH_DIR")) {
      path = d;
      keep = true;
    } else {
      path = fs::temp_directory_path() / ("shimmer-metrics-bench-" + std::to_string(::getpid()));
    }
    fs::create_directories(path);
  }
  ~BenchDir() {
    std::error_code ec;
    if (!keep) fs::remove_all(path, ec);
  }
};

BenchDir& Dir() {
  static BenchDir dir;
  return dir;
}

// Highlights on a dark background, drifting right 1.5 px per frame; the test
// adds frame-to-frame flicker to the highlights, as an unfiltered NDF does.
void WriteSequence(const fs::path& dir, int width, int height, int frames, bool flicker) {
  if (fs::exists(dir / "done")) return;
  fs::create_directories(dir);
  std::mt19937 rng(flicker ? 1 : 2);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  cv::Mat spec(height, width, CV_32F), diffuse(height, width, CV_32F), mx(height, width, CV_32F, cv::Scalar(-1.5)),
      my(height, width, CV_32F, cv::Scalar(0.0));
  for (int t = 0; t < frames; ++t) {
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const double u = (x - 1.5 * t) * 0.05, v = y * 0.05;
        const double lobe = std::pow(std::max(0.0, std::sin(u) * std::cos(v)), 40.0) * 20.0;
        const float f = flicker ? 1.0f + 0.3f * noise(rng) : 1.0f;
        spec.at<float>(y, x) = static_cast<float>(lobe) * f;
        diffuse.at<float>(y, x) = static_cast<float>(0.18 + 0.02 * std::sin(0.01 * x));
      }
    cv::Mat beauty = spec + diffuse;
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.exr", t);
    shimmer::Status s =
        shimmer::WriteExr(dir / name, width, height,
                          {m::PlaneOf("R", beauty), m::PlaneOf("G", beauty), m::PlaneOf("B", beauty),
                           m::PlaneOf("specular.R", spec), m::PlaneOf("specular.G", spec),
                           m::PlaneOf("specular.B", spec), m::PlaneOf("motion.X", mx), m::PlaneOf("motion.Y", my)});
    if (!s) {
      std::fprintf(stderr, "%s\n", s.error().c_str());
      std::exit(1);
    }
  }
  std::FILE* f = std::fopen((dir / "done").c_str(), "w");
  if (f) std::fclose(f);
}

// The test and reference sequences of one size, written on first use.
struct Sequences {
  fs::path test, ref;
  int width = 0, height = 0, frames = 0;
};
Sequences Prepare(const benchmark::State& state) {
  Sequences s;
  s.width = static_cast<int>(state.range(0));
  s.height = static_cast<int>(state.range(1));
  s.frames = static_cast<int>(state.range(2));
  const fs::path base = Dir().path / (std::to_string(s.width) + "x" + std::to_string(s.height));
  s.test = base / "test";
  s.ref = base / "ref";
  WriteSequence(s.test, s.width, s.height, s.frames, true);
  WriteSequence(s.ref, s.width, s.height, s.frames, false);
  return s;
}

void Rates(benchmark::State& state, const Sequences& s) {
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(s.frames), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["Mpix/s"] = benchmark::Counter(static_cast<double>(s.frames) * s.width * s.height / 1e6,
                                                benchmark::Counter::kIsIterationInvariantRate);
}

void BM_MetricsPass(benchmark::State& state) {
  const Sequences s = Prepare(state);
  m::MetricsOptions options{.test = s.test, .reference = s.ref};
  for (auto _ : state) {
    auto report = m::ComputeMetrics(options);
    if (!report) {
      state.SkipWithError(report.error().c_str());
      return;
    }
    benchmark::DoNotOptimize(report->tv_err);
  }
  Rates(state, s);
}

// The channels the pass decodes (exr_sequence.cpp's ReadFrame): the specular
// layer's R, G, B, and for the test frames motion.X/Y, into float planes.
void BM_DecodeOnly(benchmark::State& state) {
  const Sequences s = Prepare(state);
  const auto inflater = state.range(3) ? shimmer::ExrZipInflater::kLibdeflate : shimmer::ExrZipInflater::kOpenExr;
  const size_t plane = static_cast<size_t>(s.width) * s.height;
  std::array<std::vector<float>, 5> planes;
  for (auto& p : planes) p.resize(plane);
  const std::array<const char*, 5> names = {"specular.R", "specular.G", "specular.B", "motion.X", "motion.Y"};
  std::vector<fs::path> files[2] = {m::OpenSequence(s.test, {})->frames, m::OpenSequence(s.ref, {})->frames};
  for (auto _ : state) {
    for (int t = 0; t < s.frames; ++t)
      for (int side = 0; side < 2; ++side) {
        auto in = shimmer::ExrInput::Open(files[side][t], /*whole_file=*/true);
        if (!in) {
          state.SkipWithError(in.error().c_str());
          return;
        }
        std::vector<shimmer::ExrPlaneRequest> requests;
        for (int c = 0; c < (side == 0 ? 5 : 3); ++c) requests.push_back({names[c], planes[c].data()});
        if (shimmer::Status read = in->Read(0, requests, inflater); !read) {
          state.SkipWithError(read.error().c_str());
          return;
        }
      }
    benchmark::DoNotOptimize(planes[0].data());
  }
  Rates(state, s);
}

// As ComputeMetrics sets it up for `shimmer metrics TEST REF` on these files.
m::AccumulatorSetup SetupFor(const Sequences& s) {
  m::AccumulatorSetup setup;
  setup.width = s.width;
  setup.height = s.height;
  setup.frames = s.frames;
  setup.fps = 60;
  setup.has_reference = true;
  setup.with_motion = true;
  setup.region = cv::Mat::ones(s.height, s.width, CV_8U);
  setup.signal = m::FlickerSignal::kError;
  setup.segment_length = std::min(s.frames, 64);
  return setup;
}

void BM_Arithmetic(benchmark::State& state) {
  const Sequences s = Prepare(state);
  const bool finish = state.range(3) != 0;
  auto test = m::OpenSequence(s.test, {});
  auto ref = m::OpenSequence(s.ref, {});
  std::vector<m::LuminanceFrame> tests, refs;
  for (int t = 0; t < s.frames; ++t) {
    tests.push_back(*m::ReadFrame(test->frames[t], test->layer, s.width, s.height, true));
    refs.push_back(*m::ReadFrame(ref->frames[t], ref->layer, s.width, s.height, false));
  }
  for (auto _ : state) {
    if (!finish) state.PauseTiming();
    {
      m::MetricsAccumulator accumulator(SetupFor(s));
      if (!finish) state.ResumeTiming();
      for (int t = 0; t < s.frames; ++t)
        accumulator.AddFrame(tests[t].luminance, refs[t].luminance, tests[t].motion, "test", "ref");
      if (finish) {
        m::MetricsReport report;
        if (shimmer::Status done = accumulator.Finish(&report); !done) {
          state.SkipWithError(done.error().c_str());
          return;
        }
        benchmark::DoNotOptimize(report.tv_err);
      }
      state.PauseTiming();
    }  // the accumulator's release is not arithmetic
    state.ResumeTiming();
  }
  // Seconds per frame pair.
  state.counters["s/pair"] = benchmark::Counter(
      static_cast<double>(s.frames), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// Only the block bootstrap of the intervals (Finish's largest part at
// 1080p): one tile row per 8x8 tile of the frame, the frames' blocks, the
// default 1000 replicates, on made-up sums.
void BM_Bootstrap(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0)), height = static_cast<int>(state.range(1));
  const int frames = static_cast<int>(state.range(2));
  const int length = m::FrameBlockLength(frames);
  std::vector<int> block_frames;
  for (int t = 0; t < frames; t += length) block_frames.push_back(std::min(length, frames - t));
  const int blocks = static_cast<int>(block_frames.size());
  m::TileBlockStatistics cells(block_frames);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> sums(m::TileBlockStatistics::kCellSums * static_cast<size_t>(blocks));
  const m::BootstrapSettings settings;
  for (int tile = 0; tile < (width / settings.tile) * (height / settings.tile); ++tile) {
    const int index = cells.AddTile();
    for (float& v : sums) v = u(rng);
    cells.AddPixel(index, u(rng), u(rng), sums.data(), u(rng), 1);
  }
  const m::TileBlockStatistics::Estimates point = cells.Evaluate({}, {});
  for (auto _ : state) {
    auto intervals = cells.Bootstrap(point, settings);
    benchmark::DoNotOptimize(intervals.tv_err);
  }
  state.counters["tiles"] = cells.tiles();
}

// Runs the numpy/scipy script on the same files and reports the time it
// measures itself. Skipped where the interpreter ($SHIMMER_PYTHON, default
// python3) lacks numpy or scipy.
void BM_NumpyBaseline(benchmark::State& state) {
  const Sequences s = Prepare(state);
  const char* python = std::getenv("SHIMMER_PYTHON");  // the interpreter that has numpy and scipy
  const std::string command = std::string(python ? python : "python3") + " '" SHIMMER_NUMPY_BASELINE "' '" +
                              s.test.string() + "' '" + s.ref.string() + "'";
  for (auto _ : state) {
    std::FILE* pipe = ::popen(command.c_str(), "r");
    std::string out;
    char buffer[4096];
    while (pipe && std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
    if (!pipe || ::pclose(pipe) != 0) {
      state.SkipWithError("python3 with numpy and scipy is needed (Debian: python3-numpy python3-scipy)");
      return;
    }
    const auto result = nlohmann::json::parse(out, nullptr, false);
    if (result.is_discarded() || !result.contains("seconds")) {
      state.SkipWithError(("unexpected output: " + out).c_str());
      return;
    }
    state.SetIterationTime(result["seconds"].get<double>());
  }
  Rates(state, s);
}

// Sizes: {width, height, frames}; the issue's two cases.
void Sizes(benchmark::internal::Benchmark* b, std::vector<int64_t> extra = {}) {
  for (const std::vector<int64_t>& size : {std::vector<int64_t>{512, 512, 64}, std::vector<int64_t>{1920, 1080, 16}}) {
    if (extra.empty()) b->Args(size);
    for (int64_t e : extra) {
      std::vector<int64_t> args = size;
      args.push_back(e);
      b->Args(args);
    }
  }
}

}  // namespace

BENCHMARK(BM_MetricsPass)
    ->Apply([](auto* b) { Sizes(b); }) -> ArgNames({"w", "h", "frames"}) -> Unit(benchmark::kMillisecond)
        -> UseRealTime() -> Iterations(3);
BENCHMARK(BM_DecodeOnly)
    ->Apply([](auto* b) {
      Sizes(b, {0, 1});
    }) -> ArgNames({"w", "h", "frames", "libdeflate"}) -> Unit(benchmark::kMillisecond) -> UseRealTime()
        -> Iterations(3);
BENCHMARK(BM_Arithmetic)
    ->Apply([](auto* b) {
      Sizes(b, {0, 1});
    }) -> ArgNames({"w", "h", "frames", "finish"}) -> Unit(benchmark::kMillisecond) -> UseRealTime() -> Iterations(3);
BENCHMARK(BM_Bootstrap)
    ->Apply([](auto* b) { Sizes(b); }) -> ArgNames({"w", "h", "frames"}) -> Unit(benchmark::kMillisecond)
        -> UseRealTime() -> Iterations(5);
BENCHMARK(BM_NumpyBaseline)
    ->Apply([](auto* b) { Sizes(b); }) -> ArgNames({"w", "h", "frames"}) -> Unit(benchmark::kMillisecond)
        -> UseManualTime() -> Iterations(3);

BENCHMARK_MAIN();
