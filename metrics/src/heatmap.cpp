#include "shimmer/metrics/heatmap.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "shimmer/core/atomic_file.h"

namespace shimmer::metrics {

namespace {

// Blue - white - red, for signed values: OpenCV has no diverging colormap, so
// build one as a user LUT for cv::applyColorMap.
cv::Mat DivergingLut() {
  cv::Mat lut(256, 1, CV_8UC3);
  const cv::Vec3d blue(180, 80, 30), white(245, 245, 245), red(40, 40, 200);  // BGR
  for (int i = 0; i < 256; ++i) {
    double t = i / 255.0;
    cv::Vec3d c = t < 0.5 ? blue + (white - blue) * (t / 0.5) : white + (red - white) * ((t - 0.5) / 0.5);
    lut.at<cv::Vec3b>(i) =
        cv::Vec3b(cv::saturate_cast<uchar>(c[0]), cv::saturate_cast<uchar>(c[1]), cv::saturate_cast<uchar>(c[2]));
  }
  return lut;
}

// Position in [0,1] of a value on the scale.
double Normalized(double v, HeatmapScaling scaling, const HeatmapRange& r) {
  if (!std::isfinite(v)) return 0;
  double t;
  if (scaling == HeatmapScaling::kLog) {
    const double lv = std::log10(std::max(v, r.lo)), llo = std::log10(r.lo), lhi = std::log10(r.hi);
    t = lhi > llo ? (lv - llo) / (lhi - llo) : 0;
  } else {
    t = r.hi > r.lo ? (v - r.lo) / (r.hi - r.lo) : 0.5;
  }
  return std::clamp(t, 0.0, 1.0);
}

std::string Label(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

HeatmapRange AutoRange(const cv::Mat& values, const cv::Mat& region, HeatmapScaling scaling) {
  cv::Mat v;
  values.convertTo(v, CV_64F);
  std::vector<double> picked;
  for (int y = 0; y < v.rows; ++y)
    for (int x = 0; x < v.cols; ++x) {
      if (!region.empty() && !region.at<uint8_t>(y, x)) continue;
      double d = v.at<double>(y, x);
      if (!std::isfinite(d)) continue;
      if (scaling == HeatmapScaling::kLog) {
        if (d > 0) picked.push_back(d);
      } else {
        picked.push_back(std::abs(d));
      }
    }
  if (scaling == HeatmapScaling::kLog) {
    double hi = Percentile(picked, 0.999);
    if (!(hi > 0)) hi = 1;
    return {hi * 1e-4, hi};
  }
  double m = Percentile(picked, 0.99);
  if (!(m > 0)) m = 1;
  return {-m, m};
}

cv::Mat ColourMap(const cv::Mat& values, HeatmapScaling scaling, const HeatmapRange& range) {
  cv::Mat v;
  values.convertTo(v, CV_64F);
  cv::Mat index(v.size(), CV_8U);
  for (int y = 0; y < v.rows; ++y)
    for (int x = 0; x < v.cols; ++x)
      index.at<uint8_t>(y, x) = cv::saturate_cast<uchar>(255.0 * Normalized(v.at<double>(y, x), scaling, range));
  cv::Mat colour;
  if (scaling == HeatmapScaling::kLog)
    cv::applyColorMap(index, colour, cv::COLORMAP_INFERNO);
  else
    cv::applyColorMap(index, colour, DivergingLut());
  return colour;
}

cv::Mat RenderHeatmap(const cv::Mat& values, const cv::Mat& region, HeatmapScaling scaling, const HeatmapRange& range,
                      const std::string& title) {
  cv::Mat colour = ColourMap(values, scaling, range);
  if (!region.empty()) colour.setTo(cv::Scalar(128, 128, 128), region == 0);
  // Enlarge small frames by an integer factor so pixels stay crisp.
  const int scale = std::max(1, 384 / std::max(1, std::max(colour.rows, colour.cols)));
  if (scale > 1) cv::resize(colour, colour, cv::Size(), scale, scale, cv::INTER_NEAREST);

  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double font_scale = 0.45;
  const int title_h = 28, bar_w = 18, gap = 10, label_w = 80, pad = 10;
  const int bar_h = std::max(colour.rows, 160);
  cv::Mat canvas(title_h + std::max(colour.rows, bar_h) + pad, colour.cols + gap + bar_w + label_w, CV_8UC3,
                 cv::Scalar(255, 255, 255));
  colour.copyTo(canvas(cv::Rect(0, title_h, colour.cols, colour.rows)));
  cv::putText(canvas, title, cv::Point(4, 19), font, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);

  // Colour bar: top = hi, bottom = lo, values sampled on the same scale.
  cv::Mat bar_values(bar_h, 1, CV_64F);
  for (int i = 0; i < bar_h; ++i) {
    double t = 1.0 - static_cast<double>(i) / (bar_h - 1);
    bar_values.at<double>(i) =
        scaling == HeatmapScaling::kLog
            ? std::pow(10.0, std::log10(range.lo) + t * (std::log10(range.hi) - std::log10(range.lo)))
            : range.lo + t * (range.hi - range.lo);
  }
  cv::Mat bar = ColourMap(bar_values, scaling, range);
  cv::resize(bar, bar, cv::Size(bar_w, bar_h), 0, 0, cv::INTER_NEAREST);
  const int bx = colour.cols + gap;
  bar.copyTo(canvas(cv::Rect(bx, title_h, bar_w, bar_h)));
  cv::rectangle(canvas, cv::Rect(bx, title_h, bar_w, bar_h), cv::Scalar(0, 0, 0));
  const int ticks = 5;
  for (int i = 0; i < ticks; ++i) {
    const double t = static_cast<double>(i) / (ticks - 1);
    const int y = title_h + static_cast<int>(std::lround((1.0 - t) * (bar_h - 1)));
    const double v = bar_values.at<double>(std::clamp(y - title_h, 0, bar_h - 1));
    cv::line(canvas, cv::Point(bx + bar_w, y), cv::Point(bx + bar_w + 4, y), cv::Scalar(0, 0, 0));
    cv::putText(canvas, Label(v), cv::Point(bx + bar_w + 6, std::clamp(y + 4, title_h + 10, canvas.rows - 2)), font,
                font_scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  if (scaling == HeatmapScaling::kLog)
    cv::putText(canvas, "log", cv::Point(bx, title_h + bar_h + 9), font, 0.35, cv::Scalar(80, 80, 80), 1, cv::LINE_AA);
  return canvas;
}

Status WriteImage(const std::filesystem::path& file, const cv::Mat& image) {
  // Encoded in memory, then written as any file is: the write's failure then
  // has the system's reason (a full disk), not the codec's.
  std::vector<unsigned char> bytes;
  try {
    if (!cv::imencode(file.extension().string(), image, bytes))
      return Status::Failure(file.string() + ": OpenCV cannot encode this image format", ErrorCode::kInternal);
  } catch (const cv::Exception& e) {
    return Status::Failure(file.string() + ": cannot encode the image (" + e.err + ")", ErrorCode::kInternal);
  }
  return WriteFileAtomic(file, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace shimmer::metrics
