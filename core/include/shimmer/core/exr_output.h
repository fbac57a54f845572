// Writing EXR frames: the one EXR writer of shimmer (rendered frames, metric
// maps, test sequences). Single part, scanlines, one named channel per plane.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "shimmer/core/result.h"

namespace shimmer {

struct ExrPlane {
  std::string name;               // e.g. "R", "specular.G", "motion.X", "Y"
  const float* pixels = nullptr;  // width * height, row-major, tightly packed
  bool half = false;              // stored as half (converted on write)
};

// ZIP for frames people keep; none for frames read once and deleted, where
// zlib costs more than producing them.
enum class ExrCompression { kNone, kZip };

// Written to a temporary name and renamed; the error names `file`.
Status WriteExr(const std::filesystem::path& file, int width, int height, const std::vector<ExrPlane>& planes,
                ExrCompression compression = ExrCompression::kZip);

}  // namespace shimmer
