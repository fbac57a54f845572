#include "shimmer/metrics/atomic_file.h"

#include <unistd.h>

#include <system_error>

namespace shimmer::metrics {

std::filesystem::path TemporaryPathFor(const std::filesystem::path& final_path) {
  std::string name(".");
  name += final_path.stem().string();
  name += ".partial-";
  name += std::to_string(::getpid());
  name += final_path.extension().string();
  return final_path.parent_path() / name;
}

Status CommitFile(const std::filesystem::path& temporary, const std::filesystem::path& final_path) {
  std::error_code ec;
  std::filesystem::rename(temporary, final_path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    return Status::Failure(final_path.string() + ": cannot write (" + ec.message() + ")");
  }
  return Ok();
}

}  // namespace shimmer::metrics
