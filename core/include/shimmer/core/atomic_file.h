// Outputs never appear half-written under their final name: they are written
// to a temporary sibling, then renamed (atomic within one file system). A
// reader sees the old file or the new one, never a torn one; a killed writer
// leaves at most a hidden ".*.partial-*" sibling.
#pragma once

#include <filesystem>
#include <string_view>

#include "shimmer/core/result.h"

namespace shimmer {

// A fresh hidden sibling of `final_path` that keeps its extension (OpenCV and
// gnuplot pick the format from it): "dir/.name.partial-<pid>-<n>.ext". Unique
// per process and call, so concurrent writers of one name never share it.
std::filesystem::path TemporaryPathFor(const std::filesystem::path& final_path);

// Renames `temporary` to `final_path`; on failure removes `temporary`.
Status CommitFile(const std::filesystem::path& temporary, const std::filesystem::path& final_path);

// Writes `bytes` to `path` through a temporary sibling and a rename. The
// error (code kIo) names `path` and the system's reason (e.g. "No space left
// on device").
Status WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes);

// `error_number`'s text, or `fallback` when it is 0 (a stream that failed
// without a system error; "Success" is never a reason).
std::string SystemReason(int error_number, const char* fallback = "unknown error");

}  // namespace shimmer
