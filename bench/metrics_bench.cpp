// Frames per second of the full `shimmer metrics` pass (read both sequences,
// variance/bias/difference/RMSE, Welch spectrum, warp error) on synthetic
// renderer-like sequences: float EXR, ZIP, beauty + specular + motion layers.
//
// The sequences are written once into $SHIMMER_BENCH_DIR (kept, so that
// bench/metrics_numpy_baseline.py can run on the same files) or into a
// temporary directory that is removed at exit.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>

#include "shimmer/metrics/exr_sequence.h"
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

void BM_MetricsPass(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0)), height = static_cast<int>(state.range(1));
  const int frames = static_cast<int>(state.range(2));
  const fs::path base = Dir().path / (std::to_string(width) + "x" + std::to_string(height));
  WriteSequence(base / "test", width, height, frames, true);
  WriteSequence(base / "ref", width, height, frames, false);
  m::MetricsOptions options{.test = base / "test", .reference = base / "ref"};
  for (auto _ : state) {
    auto report = m::ComputeMetrics(options);
    if (!report) {
      state.SkipWithError(report.error().c_str());
      return;
    }
    benchmark::DoNotOptimize(report->tv_err);
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["Mpix/s"] = benchmark::Counter(static_cast<double>(frames) * width * height / 1e6,
                                                benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

BENCHMARK(BM_MetricsPass)->Args({512, 512, 64})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
BENCHMARK(BM_MetricsPass)->Args({1920, 1080, 16})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

BENCHMARK_MAIN();
