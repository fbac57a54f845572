#include "shimmer/core/host_memory.h"

#include <fstream>
#include <limits>
#include <string>

namespace shimmer {

std::uint64_t AvailableHostMemory() {
  std::ifstream meminfo("/proc/meminfo");
  for (std::string key; meminfo >> key;) {
    std::uint64_t kib = 0;
    meminfo >> kib;
    if (key == "MemAvailable:") return kib * 1024;
    meminfo.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return 0;
}

}  // namespace shimmer
