// Renderer cost at 512x512 on whatever Vulkan device is picked (lavapipe on
// the project machine): GPU milliseconds per frame from timestamps for `none`
// and every filter variant, shaded samples per second for the 16x16
// reference, and where the rest of the time goes (shader compile, pipeline
// creation and first-dispatch JIT, read-back, EXR write).
// `stages/...` time cut-down copies of the kernel (render.comp with parts
// replaced, through the renderer's source overrides), each cut adding to the
// one before: the differences say where a 1-spp frame's and a reference
// sample's time goes (scripts/speed_report.py tabulates them).
//   XDG_RUNTIME_DIR=/tmp build/bench/renderer_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"
#include "test_hooks.h"

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

// A cut of the kernel: text of render.comp and what replaces it.
struct Cut {
  std::string from, to;
};

// The 1-spp frame (shadePixelCentre), each stage cutting one more part.
const std::vector<std::pair<std::string, std::vector<Cut>>>& FrameStages() {
  static const auto* stages = new std::vector<std::pair<std::string, std::vector<Cut>>>{
      {"no-aovs", {{"  writeAovs(idx, px, s, sh, prev);\n}", "}"}}},
      // The variant's NDF and the BRDF: the sample's normal and the
      // footprint's half vector stand in for the shade.
      {"no-shading",
       {{"  PixelShade sh = shadeSample(s, f, ndf, m, light, VARIANT_ID, vp, QUADRATURE);",
         "  PixelShade sh; sh.specular = s.n + vec3(f.hpp, 0.0); sh.diffuse = vec3(s.t);"}}},
      // The quad exchange and the footprint (the exchanged samples and the
      // neighbours' rays continued onto the primitive) go dead.
      {"no-footprint", {{"sh.specular = s.n + vec3(f.hpp, 0.0);", "sh.specular = s.n;"}}},
      // The bounded primitives (the tile's list): the ray tests the planes
      // alone.
      {"planes-only",
       {{"  SurfaceSample s = surfaceOfHit(traceTile(ray.o, ray.d), ray, light);",
         "  SurfaceSample s = surfaceOfHit(unboundedHit(ray.o, ray.d), ray, light);"}}},
      // The surface at the hit (position, normals, frame, light): the hit's
      // distance and the ray stand in.
      {"no-surface",
       {{"  SurfaceSample s = surfaceOfHit(unboundedHit(ray.o, ray.d), ray, light);",
         "  SurfaceSample s = missedSample(); s.t = unboundedHit(ray.o, ray.d).t; s.n = ray.d;"}}},
      // The camera ray and the planes' test: what is left is the
      // invocation, its pixel and the channel writes.
      {"no-trace",
       {{"  SurfaceSample s = missedSample(); s.t = unboundedHit(ray.o, ray.d).t; s.n = ray.d;\n"
         "  if ((SCENE_FEATURES & SCENE_ROUGHNESS_MAPS) != 0) m = materialAt(m, s);\n  ShadingFootprint f;",
         "  SurfaceSample s = missedSample();\n  ShadingFootprint f;"}}},
  };
  return *stages;
}

// The reference's sample loop (replicateSums, addSample), the same way.
const std::vector<std::pair<std::string, std::vector<Cut>>>& ReferenceStages() {
  static const auto* stages = new std::vector<std::pair<std::string, std::vector<Cut>>>{
      {"no-shading",
       {{"  PixelShade sh = shadeSample(s, f, sampleNdf(s, f, m, vp), m, light, VARIANT_ID, vp, u);\n"
         "  a.spec += sh.specular;\n  a.diff += sh.diffuse;",
         "  a.spec += s.n;\n  a.diff += vec3(s.t);"}}},
      // The trace against the pixel's candidates (and the walk of the few
      // pixels with too many): the ray stands in for the surface.
      {"no-trace",
       {{"    SurfaceSample s0 = tracePixelRay(candidates, ray0, light);\n"
         "    SurfaceSample s1 = tracePixelRay(candidates, ray1, light);",
         "    SurfaceSample s0 = missedSample(); s0.n = ray0.d; s0.t = ray0.o.x;\n"
         "    SurfaceSample s1 = missedSample(); s1.n = ray1.d; s1.t = ray1.o.x;"},
        {"sums = addSample(sums, traceRay(ray, light), ray, light, m, vp, lightNumbers(seed, k));",
         "sums.spec += ray.d;"}}},
      // The sample's ray (its jitter's two hashes): what is left is the
      // loop, the pixel's candidate walk and the replicate's bookkeeping.
      {"no-ray",
       {{"    Ray ray0 = sampleRay(c, px, seed, k);\n    Ray ray1 = sampleRay(c, px, seed, k + 1);",
         "    Ray ray0; ray0.o = vec3(float(k)); ray0.d = vec3(1.0);\n    Ray ray1 = ray0;"}}},
  };
  return *stages;
}

std::string KernelText() {
  std::ifstream in(SHIMMER_RENDER_COMP);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// render.comp with the cuts of stages[0..last]; "" with *error set when a
// cut no longer matches the kernel's text.
std::string CutKernel(const std::vector<std::pair<std::string, std::vector<Cut>>>& stages, std::size_t last,
                      std::string* error) {
  std::string text = KernelText();
  if (text.empty()) {
    *error = std::string("cannot read ") + SHIMMER_RENDER_COMP;
    return "";
  }
  for (std::size_t i = 0; i <= last; ++i)
    for (const Cut& cut : stages[i].second) {
      const auto at = text.find(cut.from);
      if (at == std::string::npos || text.find(cut.from, at + 1) != std::string::npos) {
        *error = "render.comp changed: stage " + stages[i].first + "'s cut does not match it once (" +
                 cut.from.substr(0, 60) + "...)";
        return "";
      }
      text.replace(at, cut.from.size(), cut.to);
    }
  return text;
}

// One stage of the 1-spp `none` quad frame, or of the reference.
void BM_Stage(benchmark::State& state, bool reference, std::size_t stage) {
  std::string error;
  const std::string kernel = CutKernel(reference ? ReferenceStages() : FrameStages(), stage, &error);
  if (kernel.empty()) {
    state.SkipWithError(error.c_str());
    return;
  }
  render::testing::TestHooks hooks;
  hooks.source_overrides = {{"render.comp", kernel}};
  render::testing::ScopedTestHooks scoped(hooks);
  if (reference)
    BM_Reference(state);
  else
    BM_Frame(state, "none", shading::DerivativeSource::kQuadFine);
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
  for (std::size_t k = 0; k < FrameStages().size(); ++k)
    benchmark::RegisterBenchmark(("stages/frame/" + FrameStages()[k].first).c_str(), BM_Stage, false, k)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond)
        ->Iterations(8);
  for (std::size_t k = 0; k < ReferenceStages().size(); ++k)
    benchmark::RegisterBenchmark(("stages/reference/" + ReferenceStages()[k].first).c_str(), BM_Stage, true, k)
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
