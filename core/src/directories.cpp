#include "shimmer/core/directories.h"

#include <unistd.h>

#include <cerrno>

#include "shimmer/core/atomic_file.h"

namespace shimmer {

namespace fs = std::filesystem;

std::vector<fs::path> MissingDirectories(const fs::path& dir) {
  std::vector<fs::path> missing;
  std::error_code ec;
  for (fs::path p = dir; !p.empty() && !fs::exists(p, ec) && p != p.parent_path(); p = p.parent_path())
    missing.push_back(p);
  return missing;
}

Status CheckCreatableDirectory(const fs::path& dir) {
  const std::vector<fs::path> missing = MissingDirectories(dir);
  fs::path existing = missing.empty() ? dir : missing.back().parent_path();
  if (existing.empty()) existing = ".";
  std::error_code ec;
  if (!fs::is_directory(existing, ec)) return Status::Failure(existing.string() + " is not a directory");
  errno = 0;
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    return Status::Failure("cannot write into " + existing.string() + " (" + SystemReason(errno) + ")", ErrorCode::kIo);
  return Ok();
}

}  // namespace shimmer
