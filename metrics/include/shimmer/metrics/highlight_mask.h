// The region where specular highlights live, from the reference's specular
// luminance: where flicker matters and where a whole-frame mean would dilute it.
#pragma once

#include "shimmer/core/result.h"
#include "shimmer/metrics/exr_sequence.h"

namespace shimmer::metrics {

struct HighlightMaskOptions {
  // A highlight is specular luminance above 1: brighter than a white
  // Lambertian surface lit by unit irradiance, i.e. above display white
  // before tone mapping. Linear, never tone-mapped, like the metrics.
  double threshold = 1.0;
  // Dilation radius in pixels (elliptical structuring element of size 2r+1):
  // a highlight that moves by a pixel between frames stays inside the mask,
  // and the dark pixels around it, where aliasing flickers, are included.
  int dilate_radius = 2;
  // A rough material can keep every pixel under the threshold. By default that
  // is an error (the user asked for highlights and there are none); batch runs
  // over many materials instead measure the whole frame and say so in
  // `region`, so one broad lobe does not stop a spec.
  bool empty_falls_back_to_frame = false;
};

// Union over frames of (Y_specular > threshold), dilated. Reads the `specular`
// layer when the sequence has one, else the sequence's own layer. Non-finite
// pixels never switch a pixel on. CV_8U, 0/1.
Result<cv::Mat> BuildHighlightMask(const ExrSequence& sequence, const HighlightMaskOptions& options);

}  // namespace shimmer::metrics
