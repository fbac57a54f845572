#include "kernel_inputs.h"

#include <algorithm>
#include <bit>

#include "shimmer/renderer/scene.h"

namespace shimmer::render {

namespace {

void Put(float* out, glm::dvec3 v, double w) {
  out[0] = float(v.x), out[1] = float(v.y), out[2] = float(v.z), out[3] = float(w);
}

gpu::Camera ToGpu(const shading::CameraDesc& c) {
  gpu::Camera g;
  Put(g.pos_tan, c.pos, c.tan_half_fov_y);
  Put(g.fwd_aspect, c.fwd, double(c.width) / double(c.height));
  Put(g.right, c.right, 0);
  Put(g.up, c.up, 0);
  return g;
}

}  // namespace

bool Adaptive(const ResolvedVariant& variant, const RenderSettings& s) {
  return variant.reference && s.reference_tolerance > 0;
}

std::array<std::int32_t, 7> KernelSpecialization(const ResolvedVariant& variant, const RenderSettings& settings) {
  return {variant.id,
          static_cast<std::int32_t>(settings.derivatives),
          variant.spp_n,
          scene::SceneFeatures(settings.scene),
          static_cast<std::int32_t>(settings.material.ndf),
          variant.reference ? 1 : 0,
          Adaptive(variant, settings) ? 1 : 0};
}

gpu::FrameConstants FrameConstantsOf(const RenderSettings& s, int index) {
  auto camera = [&](int frame) { return scene::CameraAt(s.camera, s.scene.rig, frame, s.fps, s.width, s.height); };
  gpu::FrameConstants f{};
  f.cam = ToGpu(camera(index));
  f.prev = ToGpu(camera(index - 1));
  const shading::LightDesc& l = s.scene.light;
  Put(f.light_a, l.vec, double(static_cast<int>(l.type)));
  Put(f.light_b, l.radiance, l.radius);
  // The NDF is specialization constant 4; a glint material's local lobe and density ride along.
  Put(f.mat_a, {s.material.alpha.x, s.material.alpha.y, s.material.glint_alpha_l}, s.material.glint_density);
  Put(f.mat_f0, s.material.f0, 0);
  Put(f.mat_albedo, s.material.albedo, 0);
  f.size[0] = s.width;
  f.size[1] = s.height;
  return f;
}

gpu::Push PushOf(const ResolvedVariant& variant, const RenderSettings& s, int index) {
  gpu::Push push{};
  const auto slots = shading::PackVariantParams(variant.params);
  std::copy_n(slots.begin(), 4, push.params);
  std::copy_n(slots.begin() + 4, 4, push.params2);
  push.round[1] = index;
  push.round[2] = s.reference_replicates;
  push.round[3] = std::bit_cast<std::int32_t>(s.seed);
  push.target[0] = Adaptive(variant, s) ? float(s.reference_tolerance) : 0.0f;
  push.target[1] = float(kReferenceLuminanceFloor);
  return push;
}

}  // namespace shimmer::render
