// Renderer cost at 512x512 on whatever Vulkan device is picked (lavapipe on
// the project machine): GPU milliseconds per frame from timestamps for `none`
// and every filter variant, shaded samples per second for the 16x16
// reference, and where the rest of the time goes (shader compile, pipeline
// creation and first-dispatch JIT, read-back, EXR write).
//   XDG_RUNTIME_DIR=/tmp build/bench/renderer_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"

namespace {

using namespace shimmer;

constexpr int kSize = 512;

// SHIMMER_BENCH_SCENE and SHIMMER_BENCH_MATERIAL (as a spec names them, e.g.
// "bumpy-plane" and "ggx:0.01") time the frame on another shot: a filter's
// cost depends on how wide its footprints are against the lobe.
// SHIMMER_BENCH_REFERENCE_SPP (16) sets the reference's N: a mesh scene's
// sample costs several times an analytic one's.
std::string FromEnvironment(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

render::RenderSettings Settings(const std::string& variant) {
  render::RenderSettings s;
  s.scene = scene::LoadScene(FromEnvironment("SHIMMER_BENCH_SCENE", "sphere-field")).value();
  const std::string material = FromEnvironment("SHIMMER_BENCH_MATERIAL", "");
  s.material = material.empty() ? s.scene.material : scene::ParseMaterial(material, s.scene.material).value();
  s.variant = variant;
  s.width = kSize;
  s.height = kSize;
  s.derivatives = shading::DerivativeSource::kQuadFine;
  return s;
}

// Frame time from GPU timestamps; the first dispatch (JIT) happened in Create.
void BM_Frame(benchmark::State& state, std::string variant, shading::DerivativeSource d) {
  render::RenderSettings s = Settings(variant);
  s.derivatives = d;
  auto created = render::Renderer::Create(s);
  if (!created) {
    state.SkipWithError(created.error().c_str());
    return;
  }
  render::Renderer* r = created->get();
  int frame = 0;
  double readback = 0;
  for (auto _ : state) {
    auto res = r->RenderFrame(frame++);
    if (!res) {
      state.SkipWithError(res.error().c_str());
      return;
    }
    state.SetIterationTime(res->gpu_ms * 1e-3);
    readback += res->readback_ms;
  }
  state.counters["readback_ms"] = readback / frame;
  state.counters["compile_ms"] = r->timings().compile_ms;
  state.counters["pipeline_ms"] = r->timings().pipeline_ms;
  state.counters["jit_ms"] = r->timings().jit_ms;
}

void BM_Reference(benchmark::State& state) {
  render::RenderSettings s = Settings("none");
  s.reference_spp = static_cast<int>(state.range(0));
  auto created = render::Renderer::Create(s);
  if (!created) {
    state.SkipWithError(created.error().c_str());
    return;
  }
  render::Renderer* r = created->get();
  int frame = 0;
  double samples = 0, seconds = 0;
  for (auto _ : state) {
    auto res = r->RenderFrame(frame++);
    if (!res) {
      state.SkipWithError(res.error().c_str());
      return;
    }
    state.SetIterationTime(res->gpu_ms * 1e-3);
    samples += double(kSize) * kSize * res->mean_spp;  // K replicates of N x N
    seconds += res->gpu_ms * 1e-3;
  }
  state.counters["Msamples_per_s"] = samples / seconds * 1e-6;
}

void BM_ExrWrite(benchmark::State& state) {
  auto created = render::Renderer::Create(Settings("none"));
  if (!created) {
    state.SkipWithError(created.error().c_str());
    return;
  }
  auto frame = (*created)->RenderFrame(0);
  if (!frame) {
    state.SkipWithError(frame.error().c_str());
    return;
  }
  auto path = (std::filesystem::temp_directory_path() / "shimmer_bench_frame.exr").string();
  for (auto _ : state) {
    Status s = render::WriteFrameExr(path, *frame, false);
    if (!s) state.SkipWithError(s.error().c_str());
  }
  std::filesystem::remove(path);
}

}  // namespace

int main(int argc, char** argv) {
  using shimmer::shading::DerivativeSource;
  benchmark::RegisterBenchmark("frame/none/quad", BM_Frame, std::string("none"), DerivativeSource::kQuadFine)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(8);
  benchmark::RegisterBenchmark("frame/none/analytic", BM_Frame, std::string("none"), DerivativeSource::kAnalytic)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(8);
  for (const auto& v : shimmer::shading::Variants()) {
    if (v.name == "none") continue;
    for (auto d : {DerivativeSource::kQuadFine, DerivativeSource::kAnalytic})
      benchmark::RegisterBenchmark(
          ("frame/" + std::string(v.name) + (d == DerivativeSource::kAnalytic ? "/analytic" : "/quad")).c_str(),
          BM_Frame, std::string(v.name), d)
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->Iterations(8);
  }
  benchmark::RegisterBenchmark("frame/supersample-2/quad", BM_Frame, std::string("supersample-2"),
                               DerivativeSource::kQuadFine)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(4);
  const int reference_spp = std::atoi(FromEnvironment("SHIMMER_BENCH_REFERENCE_SPP", "16").c_str());
  benchmark::RegisterBenchmark("reference", BM_Reference)
      ->Arg(reference_spp > 0 ? reference_spp : 16)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(3);
  benchmark::RegisterBenchmark("exr_write_512", BM_ExrWrite)->Unit(benchmark::kMillisecond)->Iterations(5);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
