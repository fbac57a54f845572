// Compiled kernels kept between processes, so that a second `shimmer render`
// of a variant skips GLSL -> SPIR-V and (where the driver caches pipelines)
// the driver's compile. Files live under $XDG_CACHE_HOME/shimmer (else
// $HOME/.cache/shimmer); SHIMMER_CACHE=off turns the cache off.
//
// A cache file is a payload behind a header that proves it whole and ours:
// magic, format version, kind, payload length, FNV-1a of the payload. A file
// that fails any check is ignored with one warning on stderr and replaced
// when the compile it would have saved has run: a cache may only make a
// process faster, never wrong, never fail.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace shimmer::render {

// The cache folder, or nothing when SHIMMER_CACHE=off or neither
// XDG_CACHE_HOME nor HOME is set. Not created here.
std::optional<std::filesystem::path> KernelCacheDirectory();

// The payload of `path` when the file exists, is of `kind` and is intact;
// nothing when it is absent. A corrupt, truncated or foreign file yields
// nothing and a warning naming the file and what is wrong with it.
std::optional<std::string> ReadCacheFile(const std::filesystem::path& path, std::string_view kind);

// Writes `payload` under `path` through a temporary name and a rename (a
// concurrent reader sees the old file or the new one), creating the folder.
// A failure (read-only home, full disk) is a warning, once per process.
void WriteCacheFile(const std::filesystem::path& path, std::string_view kind, std::string_view payload);

// Removes the oldest files of `folder` (by modification time) until the rest
// take at most `max_bytes`: stale kernels of older shimmer versions would
// otherwise pile up forever.
void TrimCacheFolder(const std::filesystem::path& folder, std::uintmax_t max_bytes);

// "shimmer: warning: <text>" on stderr, each distinct text once per process.
void WarnCache(const std::string& text);
// The warning for a cache file that is not used: its path, why, and that it
// will be rebuilt.
void WarnIgnoredCacheFile(const std::filesystem::path& path, const std::string& why);

}  // namespace shimmer::render
