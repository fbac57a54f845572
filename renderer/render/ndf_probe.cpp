// ProbeNdf: ndf_probe.comp dispatched once; CheckUserVariant: the render
// kernel compiled with a user file.
#include <cstring>

#include "pipeline_cache.h"
#include "shimmer/renderer/renderer.h"

namespace shimmer::render {

Result<shading::FilteredNdf<double>> ProbeNdf(const NdfProbe& probe) {
  auto kernel = KernelSpirv("ndf_probe.comp", probe.user.get(), /*sg_light=*/false, /*meshes=*/false, nullptr);
  if (!kernel) return kernel.failure();
  vk::ContextOptions options;
  options.device_name = probe.device;
  auto device = AcquireDevice(options);
  if (!device) return device.failure();
  const vk::BufferKind bindings[] = {vk::BufferKind::kStorage};
  const std::int32_t specialization[] = {probe.user ? 0 : probe.variant_id};
  // One dispatch: the driver's own specialization costs less than freezing
  // the constants into a module first.
  auto pipeline = AcquirePipeline(*device, *kernel, specialization, bindings, 0, nullptr, /*driver_specializes=*/true);
  if (!pipeline) return pipeline.failure();
  auto buffer = device->context->CreateBuffer(11 * 4 * sizeof(float));
  if (!buffer) return buffer.failure();
  const shading::Footprint<double>& f = probe.footprint;
  const auto slots = shading::PackVariantParams(probe.params);  // words 7 and 8
  // The layout ndf_probe.comp reads: words 0..9.
  const double in[10][4] = {{f.hpp.x, f.hpp.y, probe.alpha.x, probe.alpha.y},
                           {f.dhpp_dx.x, f.dhpp_dx.y, f.dhpp_dy.x, f.dhpp_dy.y},
                           {f.n.x, f.n.y, f.n.z, double(int(probe.ndf))},
                           {f.dn_dx.x, f.dn_dx.y, f.dn_dx.z, 0},
                           {f.dn_dy.x, f.dn_dy.y, f.dn_dy.z, 0},
                           {f.dng_dx.x, f.dng_dx.y, f.dng_dx.z, 0},
                           {f.dng_dy.x, f.dng_dy.y, f.dng_dy.z, 0},
                           {slots[0], slots[1], slots[2], slots[3]},
                           {slots[4], slots[5], slots[6], slots[7]},
                           {f.dh_dx.x, f.dh_dx.y, f.dh_dy.x, f.dh_dy.y}};
  auto* words = static_cast<float*>((*buffer)->data());
  for (int i = 0; i < 10; ++i)
    for (int c = 0; c < 4; ++c) words[4 * i + c] = float(in[i][c]);
  for (int c = 0; c < 4; ++c) words[40 + c] = 0;
  vk::Buffer* buffers[] = {buffer->get()};
  if (auto done = device->context->Dispatch(**pipeline, buffers, {}, 1, 1); !done)
    return Prefixed("ndf probe", done.failure());
  shading::FilteredNdf<double> r;
  r.slope_density = words[40];
  r.density = words[41];
  r.alpha_eff = {words[42], words[43]};
  return r;
}

Status CheckUserVariant(const shading::UserVariant& user) {
  auto kernel = KernelSpirv("render.comp", &user, /*sg_light=*/false, /*meshes=*/false, nullptr);
  if (!kernel) return kernel.failure();
  return Ok();
}

}  // namespace shimmer::render
