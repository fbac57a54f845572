// Outputs never appear half-written under their final name: write to a
// temporary sibling, then rename (atomic within one file system).
#pragma once

#include <filesystem>

#include "shimmer/metrics/result.h"

namespace shimmer::metrics {

// A sibling of `final_path` that keeps its extension (OpenCV picks the image
// and video format from it): "dir/.name.partial-<pid>.ext".
std::filesystem::path TemporaryPathFor(const std::filesystem::path& final_path);

// Renames `temporary` to `final_path`; on failure removes `temporary`.
Status CommitFile(const std::filesystem::path& temporary, const std::filesystem::path& final_path);

}  // namespace shimmer::metrics
