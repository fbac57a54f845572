// Per-pixel maps as colour-mapped PNGs with a legend (OpenCV colormaps), so a
// map can be read without the EXR beside it.
#pragma once

#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

#include "shimmer/core/result.h"

namespace shimmer::metrics {

enum class HeatmapScaling {
  kLog,     // magnitudes over decades (variances): log10, inferno
  kSigned,  // signed around 0 (bias): linear, symmetric blue-white-red
};

struct HeatmapRange {
  double lo = 0, hi = 1;
};

// Range from the region's values: kLog spans [hi 1e-4, hi] with hi the 99.9th
// percentile of the positive values (one hot pixel does not wash out the
// rest); kSigned spans [-m, m] with m the 99th percentile of |v|.
HeatmapRange AutoRange(const cv::Mat& values, const cv::Mat& region, HeatmapScaling scaling);

// BGR image: the colour-mapped values (pixels outside `region` mid grey), a
// title above, a colour bar with labelled ticks on the right. Small frames are
// enlarged (nearest neighbour) so that the legend stays legible.
cv::Mat RenderHeatmap(const cv::Mat& values, const cv::Mat& region, HeatmapScaling scaling, const HeatmapRange& range,
                      const std::string& title);

// Just the colour-mapped pixels, no legend (video frames).
cv::Mat ColourMap(const cv::Mat& values, HeatmapScaling scaling, const HeatmapRange& range);

// cv::imwrite to a temporary name, then rename.
Status WriteImage(const std::filesystem::path& file, const cv::Mat& image);

}  // namespace shimmer::metrics
