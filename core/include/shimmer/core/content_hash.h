// A fixed 64-bit hash of bytes (FNV-1a), for names derived from content:
// job ids, cache keys. Stable across builds, machines and versions, which
// std::hash is not; not meant to resist a chosen collision.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace shimmer {

std::uint64_t Fnv1a64(std::string_view bytes);
// The hash as 16 lower-case hex digits.
std::string Fnv1a64Hex(std::string_view bytes);

}  // namespace shimmer
