// Nanoseconds per filtered-NDF evaluation of each variant on the CPU (float),
// through the same GLSL the renderer runs.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "shimmer/shading/shading.h"

namespace {

using namespace shimmer::shading;

struct Input {
  glm::vec2 alpha;
  Footprint<float> footprint;
};

// A fixed spread of roughness, slopes and footprints, like a frame's pixels.
const std::vector<Input>& Inputs() {
  static const std::vector<Input> inputs = [] {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<Input> v(1024);
    for (Input& in : v) {
      const float a = 0.001f + 0.5f * u(rng) * u(rng);
      in.alpha = {a, a};
      in.footprint.hpp = {(u(rng) - 0.5f) * 0.5f, (u(rng) - 0.5f) * 0.5f};
      in.footprint.dhpp_dx = {0.05f * u(rng), 0.01f * u(rng)};
      in.footprint.dhpp_dy = {0.01f * u(rng), 0.05f * u(rng)};
      in.footprint.dn_dx = {0.05f * u(rng), 0.01f * u(rng), 0};
      in.footprint.dn_dy = {0.01f * u(rng), 0.05f * u(rng), 0};
      in.footprint.dng_dx = in.footprint.dn_dx;
      in.footprint.dng_dy = in.footprint.dn_dy;
    }
    return v;
  }();
  return inputs;
}

void BM_Variant(benchmark::State& state) {
  const VariantInfo& info = Variants()[state.range(0)];
  const Params<double> d = ResolveParams(info, {}).value();
  const Params<float> params = ParamsCast<float>(d);
  const auto& inputs = Inputs();
  for (auto _ : state) {
    for (const Input& in : inputs) {
      auto r = EvaluateVariant<float>(info.id, Ndf::kGgx, in.alpha, in.footprint, params);
      benchmark::DoNotOptimize(r);
    }
  }
  state.SetItemsProcessed(state.iterations() * inputs.size());
  state.SetLabel(std::string(info.name));
}

void AllVariants(benchmark::internal::Benchmark* b) {
  for (size_t i = 0; i < Variants().size(); ++i) b->Arg(int(i));
}

BENCHMARK(BM_Variant)->Apply(AllVariants);

}  // namespace

BENCHMARK_MAIN();
