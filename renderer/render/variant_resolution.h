// RenderSettings' variant, parameters and reference options resolved into
// what the kernel is specialised to and what sequence.json records.
#pragma once

#include "shimmer/core/result.h"
#include "shimmer/renderer/renderer.h"

namespace shimmer::render {

// The error names the setting ("variant", "reference_spp", a parameter).
Result<ResolvedVariant> ResolveVariant(const RenderSettings& settings);

}  // namespace shimmer::render
