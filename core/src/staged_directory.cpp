#include "shimmer/core/staged_directory.h"

#include <unistd.h>

#include <atomic>

#include "shimmer/core/atomic_file.h"
#include "shimmer/core/directories.h"

namespace shimmer {

namespace fs = std::filesystem;

Result<std::unique_ptr<StagedDirectory>> StagedDirectory::Create(const fs::path& out) {
  using R = Result<std::unique_ptr<StagedDirectory>>;
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    return R::Failure(out.string() + ": exists and is not a directory");
  // `out` and each missing parent, deepest first: removed again unless committed.
  std::vector<fs::path> created = MissingDirectories(out);
  auto remove_created = [&created] {
    std::error_code ignored;
    for (const fs::path& p : created) fs::remove(p, ignored);  // only when empty
  };
  // "" is the working directory, and names its files without a "./".
  ec.clear();
  if (!out.empty()) fs::create_directories(out, ec);
  if (ec) {
    remove_created();
    // A file where a directory should be is the user's path; anything else (permissions, space) is the system.
    const ErrorCode code =
        ec == std::errc::not_a_directory || ec == std::errc::file_exists ? ErrorCode::kBadInput : ErrorCode::kIo;
    return R::Failure(out.string() + ": cannot create the directory (" + ec.message() + ")", code);
  }
  static std::atomic<int> counter{0};
  const fs::path staging =
      out / (".staging-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1)));
  fs::create_directory(staging, ec);
  if (ec) {
    remove_created();
    return R::Failure(out.string() + ": cannot write into the directory (" + ec.message() + ")", ErrorCode::kIo);
  }
  return std::unique_ptr<StagedDirectory>(new StagedDirectory(out, staging, std::move(created)));
}

StagedDirectory::~StagedDirectory() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (!committed_)
    for (const fs::path& p : created_) fs::remove(p, ec);  // only when empty
}

Status StagedDirectory::Write(const std::string& name, std::string_view text) {
  return WriteFileAtomic(staging_ / name, text);
}

Status StagedDirectory::Commit(const std::string& last) {
  std::error_code ec;
  std::vector<fs::path> files;
  for (fs::directory_iterator it(staging_, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec) && it->path().filename() != last) files.push_back(it->path());
  if (ec) return Status::Failure(staging_.string() + ": cannot list (" + ec.message() + ")", ErrorCode::kIo);
  if (fs::exists(staging_ / last, ec)) files.push_back(staging_ / last);
  // Renames within one file system need no space: a full disk cannot stop them halfway.
  for (const fs::path& f : files) {
    fs::rename(f, out_ / f.filename(), ec);
    if (ec)
      return Status::Failure((out_ / f.filename()).string() + ": cannot write (" + ec.message() + ")", ErrorCode::kIo);
  }
  committed_ = true;
  return Ok();
}

Error StagedDirectory::Unstaged(const Error& error) const {
  Error out = error;
  std::string staged = staging_.string(), final_dir = out_.string();
  if (final_dir.empty()) staged += "/";
  for (std::size_t p = 0; (p = out.message.find(staged, p)) != std::string::npos; p += final_dir.size())
    out.message.replace(p, staged.size(), final_dir);
  return out;
}

}  // namespace shimmer
