// Storage for big arrays read at random, backed by transparent huge pages: the builder's collapse loop
// visits vertices in cost order over hundreds of MB, the refinement engine's operations touch records
// and faces megabytes apart. With 4 KiB pages nearly every such read also misses the TLB (a nested page
// walk under a hypervisor), so these arrays go on 2 MiB pages. Linux only asks (madvise, before the first
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

inline size_t huge_block_bytes(size_t bytes) { return (bytes + kHugePage - 1) & ~(kHugePage - 1); }

// At least `bytes` (>= kHugePage) aligned to 2 MiB, asked for huge pages; nullptr when out of memory.
// Malloc's memory: free() releases it.
inline void* allocate_on_huge_pages(size_t bytes) {
  const size_t rounded = huge_block_bytes(bytes);
  if (rounded < bytes) return nullptr;  // wrapped: no such block exists
  void* p = std::aligned_alloc(kHugePage, rounded);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (p) madvise(p, rounded, MADV_HUGEPAGE);  // advice only: failure leaves ordinary pages
#endif
  return p;
}

// A freed block of `bytes` (a multiple of kHugePage) that the next request for the same size and kind
// takes back with its pages still mapped (recycled_blocks.cpp); nullptr when none. Kind 0: blocks of
// allocate_on_huge_pages (RecycledVector). Other kinds: blocks of map_zeroed, for arrays that are never
// initialised as a whole (spm/slot_array.h), so the next array may read what the last one left and a
// block goes back only to its own kind.
void* take_recycled_block(size_t bytes, int kind = 0);
void recycle_block(void* block, size_t bytes, int kind = 0);
// `bytes` (a multiple of kHugePage) of zeros, 2 MiB aligned, asked for huge pages; a page is touched
// when first written. nullptr when out of memory; unmap_zeroed releases it.
void* map_zeroed(size_t bytes);
void unmap_zeroed(void* block, size_t bytes);

// kRecycle: a freed block goes back to recycle_block, for arrays that the next object of the same
// kind asks for again at the same size (a fresh mesh over the same hierarchy).
template <class T, bool kRecycle = false>
struct HugePageAllocator {
  using value_type = T;
  template <class U>
  struct rebind {
    using other = HugePageAllocator<U, kRecycle>;
  };

  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U, kRecycle>&) {}

  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    if (bytes < kHugePage) return std::allocator<T>().allocate(n);
    void* p = kRecycle ? take_recycled_block(huge_block_bytes(bytes), 0) : nullptr;
    if (!p) p = allocate_on_huge_pages(bytes);
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) {
    const size_t bytes = n * sizeof(T);
    if (bytes < kHugePage) return std::allocator<T>().deallocate(p, n);
    if (kRecycle) return recycle_block(p, huge_block_bytes(bytes), 0);
    std::free(p);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U, kRecycle>&) const {
    return true;
  }
};

template <class T>
using BigVector = std::vector<T, HugePageAllocator<T>>;
// The refinement engine's per-mesh arrays: a mesh made after another one freed its arrays gets their
// pages back instead of faulting in new ones (docs/internals.md, "Fresh meshes and memory").
template <class T>
using RecycledVector = std::vector<T, HugePageAllocator<T, true>>;

}  // namespace pms
