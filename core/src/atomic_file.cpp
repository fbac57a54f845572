#include "shimmer/core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

namespace shimmer {

namespace fs = std::filesystem;

std::string SystemReason(int error_number, const char* fallback) {
  return error_number == 0 ? std::string(fallback) : std::string(std::strerror(error_number));
}

fs::path TemporaryPathFor(const fs::path& final_path) {
  static std::atomic<unsigned> counter{0};
  std::string name(".");
  name += final_path.stem().string();
  name += ".partial-";
  name += std::to_string(::getpid());
  name += '-';
  name += std::to_string(counter.fetch_add(1));
  name += final_path.extension().string();
  return final_path.parent_path() / name;
}

Status CommitFile(const fs::path& temporary, const fs::path& final_path) {
  std::error_code ec;
  fs::rename(temporary, final_path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    return Status::Failure(final_path.string() + ": cannot write (" + ec.message() + ")", ErrorCode::kIo);
  }
  return Ok();
}

Status WriteFileAtomic(const fs::path& path, std::string_view bytes) {
  const fs::path temporary = TemporaryPathFor(path);
  auto fail = [&](int error_number) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    return Status::Failure(path.string() + ": cannot write (" + SystemReason(error_number) + ")", ErrorCode::kIo);
  };
  errno = 0;
  std::FILE* out = std::fopen(temporary.c_str(), "wb");
  if (!out) return fail(errno);
  errno = 0;
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), out) == bytes.size() && std::fflush(out) == 0;
  const int write_errno = errno;
  // fclose reports a deferred write error (NFS, a full disk) too.
  errno = 0;
  const bool closed = std::fclose(out) == 0;
  if (!written) return fail(write_errno);
  if (!closed) return fail(errno);
  return CommitFile(temporary, path);
}

}  // namespace shimmer
