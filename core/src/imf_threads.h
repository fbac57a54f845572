// OpenEXR's C++ library compresses and decompresses line blocks on a global
// thread pool that is empty until someone sizes it; the writer and the
// reader's Imf fallback both want it sized to the machine, once.
#pragma once

#include <ImfThreading.h>

#include <algorithm>
#include <mutex>
#include <thread>

namespace shimmer::detail {

inline void UseImfThreadPool() {
  static std::once_flag pool;
  std::call_once(
      pool, [] { Imf::setGlobalThreadCount(static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))); });
}

}  // namespace shimmer::detail
