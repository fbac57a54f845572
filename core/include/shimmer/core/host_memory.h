// How much host memory a run can count on, for refusing work that cannot fit
// before it is started (the allocation itself may succeed and its first use
// bring the OOM killer).
#pragma once

#include <cstdint>

namespace shimmer {

// MemAvailable of /proc/meminfo: what the system can give without swapping,
// in bytes; 0 when unknown.
std::uint64_t AvailableHostMemory();

}  // namespace shimmer
