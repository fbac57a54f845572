// Store rows with known numbers, for the tests of the store and the report.
#pragma once

#include <string>

#include "shimmer/experiments/job.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/shading/shading.h"

namespace shimmer::experiments::testing {

// A finished job of `variant` on sphere / ggx:0.02 / orbit at 32x32x8 with the
// given fp_max and tv_ratio (tv_err 0.5, flicker_index 0.25, 1.5 ms/frame).
inline JobResult MakeResult(const std::string& variant, double fp_max, double tv_ratio) {
  JobResult r;
  r.job.scene = "sphere";
  r.job.material = "ggx:0.02";
  r.job.camera = "orbit";
  r.job.variant = variant;
  r.job.params = {{"fp_max", fp_max}};
  r.job.derivatives = "quad";
  r.job.width = r.job.height = 32;
  r.job.frames = 8;
  r.job.fps = 30;
  r.job.reference.spp = 4;
  r.job.reference.tolerance = 0;
  // Rows of variants given parameters they lack (`none` with fp_max) do not
  // resolve: they keep the ids of their description.
  const auto sources = SourcesOf(r.job);
  r.id = JobId(r.job);
  r.reference_id = ReferenceId(r.job);
  if (sources) r.sources = sources->ToJson();
  r.metrics = {{"tv_ratio", tv_ratio}, {"tv_err", 0.5}, {"flicker", {{"flicker_index", 0.25}}}};
  r.gpu_ms_per_frame = 1.5;
  r.revision = "abc";
  r.core_version = sources ? sources->test.kernel : std::string("unresolved");
  return r;
}

}  // namespace shimmer::experiments::testing
