#include "shimmer/experiments/output_files.h"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>

#include "shimmer/core/atomic_file.h"

namespace shimmer::experiments {

namespace fs = std::filesystem;

Result<std::unique_ptr<StagedDirectory>> StagedDirectory::Create(const fs::path& out) {
  using R = Result<std::unique_ptr<StagedDirectory>>;
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    return R::Failure(out.string() + ": exists and is not a directory");
  const bool created = !fs::exists(out, ec);
  fs::create_directories(out, ec);
  if (ec) return R::Failure(out.string() + ": cannot create the directory (" + ec.message() + ")", ErrorCode::kIo);
  static std::atomic<int> counter{0};
  const fs::path staging =
      out / (".staging-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1)));
  fs::create_directory(staging, ec);
  if (ec) {
    if (created) fs::remove(out, ec);
    return R::Failure(out.string() + ": cannot write into the directory (" + ec.message() + ")", ErrorCode::kIo);
  }
  return std::unique_ptr<StagedDirectory>(new StagedDirectory(out, staging, created));
}

StagedDirectory::~StagedDirectory() {
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (!committed_ && created_out_) fs::remove(out_, ec);  // only when empty
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
      return Status::Failure((out_ / f.filename()).string() + ": cannot write (" + ec.message() + ")",
                             ErrorCode::kIo);
  }
  committed_ = true;
  return Ok();
}

std::string Slug(const std::string& s) {
  std::string out;
  for (char c : s) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

std::string FormatNumber(double v, const char* format) {
  if (std::isnan(v)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string GnuplotString(std::string_view text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

}  // namespace shimmer::experiments
