// Energy bias: does a filter make highlights darker or brighter overall?
// Specular AA that widens roughness spreads a highlight; a normalized NDF keeps
// its energy, a broken one does not, and that shows here rather than in RMSE.
#pragma once

#include <optional>

#include <opencv2/core.hpp>

namespace shimmer::metrics {

// (sum T - sum R) / sum R, signed; empty when sum R == 0 (no energy to
// compare against: reported as null rather than as a made-up number).
std::optional<double> RelativeBias(double sum_test, double sum_reference);

// Per pixel (mean_t T - mean_t R) / mean_t R over the frames (CV_32F);
// 0 where the pixel is outside `region`, excluded, or its reference is 0.
cv::Mat EnergyBiasMap(const cv::Mat& mean_test, const cv::Mat& mean_reference, const cv::Mat& region,
                      const cv::Mat& excluded);

}  // namespace shimmer::metrics
