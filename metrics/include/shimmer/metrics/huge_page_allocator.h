// An allocator for the metrics pass's big per-pixel arrays (the bootstrap's
// cells, the spectrum's frame ring: hundreds of MiB at 1080p) that asks the
// kernel for transparent huge pages.
//
// Why: zero-filling such an array faults in one 4 KiB page at a time, and in
// a virtual machine a page fault costs microseconds: tens of thousands of
// them were a tenth of a 512x512 x 64 pass. With 2 MiB pages there are 512
// times fewer. Linux's transparent_hugepage "madvise" mode (the default of
// Debian's kernels) gives them only to regions marked with MADV_HUGEPAGE
// (madvise(2)); elsewhere the hint is ignored and nothing changes.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

namespace shimmer::metrics {

template <class T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr size_t kPage = size_t{2} << 20;

  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}  // NOLINT: rebinding, as std::allocator

  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    if (bytes < kPage) return static_cast<T*>(::operator new(bytes));
    const size_t rounded = (bytes + kPage - 1) / kPage * kPage;
    void* p = std::aligned_alloc(kPage, rounded);
    if (!p) throw std::bad_alloc();
    ::madvise(p, rounded, MADV_HUGEPAGE);
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) {
    if (n * sizeof(T) < kPage)
      ::operator delete(p);
    else
      std::free(p);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const {
    return true;
  }
};

template <class T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace shimmer::metrics
