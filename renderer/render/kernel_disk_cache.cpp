#include "kernel_disk_cache.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <mutex>
#include <set>
#include <sstream>
#include <system_error>
#include <vector>

#include "shimmer/core/atomic_file.h"
#include "shimmer/core/content_hash.h"

namespace shimmer::render {

namespace fs = std::filesystem;

namespace {

// Version 1 of the file layout: one text line, then the payload.
//   "shimmer-cache 1 <kind> <payload bytes> <FNV-1a 64 of the payload, hex>\n"
constexpr std::string_view kMagic = "shimmer-cache";
constexpr int kFormat = 1;

std::string HeaderOf(std::string_view kind, std::string_view payload) {
  return std::string(kMagic) + " " + std::to_string(kFormat) + " " + std::string(kind) + " " +
         std::to_string(payload.size()) + " " + Fnv1a64Hex(payload) + "\n";
}

}  // namespace

std::optional<fs::path> KernelCacheDirectory() {
  if (const char* off = std::getenv("SHIMMER_CACHE"); off && std::string_view(off) == "off") return std::nullopt;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return fs::path(xdg) / "shimmer";
  if (const char* home = std::getenv("HOME"); home && *home) return fs::path(home) / ".cache" / "shimmer";
  return std::nullopt;
}

void WarnCache(const std::string& text) {
  static std::mutex mutex;
  static auto* said = new std::set<std::string>;  // leaked: warnings may come from exit-time threads
  std::lock_guard lock(mutex);
  if (said->insert(text).second) std::fprintf(stderr, "shimmer: warning: %s\n", text.c_str());
}

void WarnIgnoredCacheFile(const fs::path& path, const std::string& why) {
  WarnCache("ignoring the kernel cache file " + path.string() + " (" + why + "); it will be rebuilt");
}

std::optional<std::string> ReadCacheFile(const fs::path& path, std::string_view kind) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;  // absent (or unreadable: treated alike, the compile runs)
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto reject = [&](const std::string& why) -> std::optional<std::string> {
    WarnIgnoredCacheFile(path, why);
    return std::nullopt;
  };
  const std::size_t eol = bytes.find('\n');
  if (eol == std::string::npos || eol > 256) return reject("no cache header");
  std::istringstream header(bytes.substr(0, eol));
  std::string magic, file_kind, hash;
  int format = 0;
  std::size_t length = 0;
  if (!(header >> magic >> format >> file_kind >> length >> hash) || magic != kMagic)
    return reject("not a shimmer cache file");
  if (format != kFormat)
    return reject("cache format " + std::to_string(format) + ", expected " + std::to_string(kFormat));
  if (file_kind != kind) return reject("holds '" + file_kind + "', expected '" + std::string(kind) + "'");
  std::string payload = bytes.substr(eol + 1);
  if (payload.size() != length)
    return reject("truncated: " + std::to_string(payload.size()) + " of " + std::to_string(length) + " bytes");
  if (Fnv1a64Hex(payload) != hash) return reject("checksum mismatch");
  return payload;
}

void WriteCacheFile(const fs::path& path, std::string_view kind, std::string_view payload) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  std::string bytes = HeaderOf(kind, payload);
  bytes.append(payload);
  if (ec) {
    WarnCache("cannot keep compiled kernels in " + path.parent_path().string() + " (" + ec.message() + ")");
    return;
  }
  if (Status s = WriteFileAtomic(path, bytes); !s)
    WarnCache("cannot keep compiled kernels in " + path.parent_path().string() + " (" + s.error() + ")");
}

void TrimCacheFolder(const fs::path& folder, std::uintmax_t max_bytes) {
  struct Entry {
    fs::file_time_type time;
    std::uintmax_t size;
    fs::path path;
  };
  std::vector<Entry> entries;
  std::uintmax_t total = 0;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code e1, e2;
    if (!it->is_regular_file(e1)) continue;
    const std::uintmax_t size = it->file_size(e1);
    const fs::file_time_type time = it->last_write_time(e2);
    if (e1 || e2) continue;
    entries.push_back({time, size, it->path()});
    total += size;
  }
  if (total <= max_bytes) return;
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.time < b.time; });
  for (const Entry& e : entries) {
    if (total <= max_bytes) break;
    std::error_code ignored;
    if (fs::remove(e.path, ignored)) total -= e.size;
  }
}

}  // namespace shimmer::render
