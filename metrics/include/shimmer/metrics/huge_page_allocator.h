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
//
// Even in 2 MiB pages the first touch is dear: the kernel zeroes each page
// as it faults it in, and vector's value-initialisation touches them all
// from one thread (a profile put a sixth of a 1080p x 16 accumulator's CPU
// time in its constructor's page faults). So an allocation faults its pages in first,
// from every core (cv::parallel_for_); the fill then runs over memory that is
// already there.
#pragma once

#include <opencv2/core.hpp>

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
    FaultIn(static_cast<char*>(p), rounded);
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) {
    if (n * sizeof(T) < kPage)
      ::operator delete(p);
    else
      std::free(p);
  }
  // One write per 4 KiB page (a page that did not become part of a huge one
  // faults on its own), the pages shared out among the threads.
  static void FaultIn(char* p, size_t bytes) {
    constexpr size_t kSmallPage = 4096;
    const int pages = static_cast<int>(bytes / kPage);
    cv::parallel_for_(cv::Range(0, pages), [p](const cv::Range& range) {
      for (size_t at = range.start * kPage; at < range.end * kPage; at += kSmallPage)
        *static_cast<volatile char*>(p + at) = 0;
    });
  }

  template <class U>
  bool operator==(const HugePageAllocator<U>&) const {
    return true;
  }
};

template <class T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace shimmer::metrics
