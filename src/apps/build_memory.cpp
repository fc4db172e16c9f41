#include "apps/build_memory.h"

#include <atomic>
#include <climits>
#include <cstdint>
#include <cstdlib>
#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>
#endif

#include "common/huge_pages.h"

namespace pms::app {
namespace {

// A build goes through phases (load, clean, simplify, pack, write) that each allocate and free arrays
// from kilobytes to hundreds of MB. Under a hypervisor a 4 KiB page fault costs several microseconds and a
// TLB miss is a nested page walk, so the build asks for fewer, larger pages:
// - blocks below 2 MiB stay on glibc's heap, which is never trimmed (each phase reuses what the last
//   one freed), is grown by its pad at once, and asks for 2 MiB pages on that pad;
// - blocks of 2 MiB and more get their own mapping, returned when freed; the binary's operator new
//   puts them on 2 MiB pages (large_allocations.cpp), so mapping them afresh costs little, and the
//   builder's big arrays, read in cost order (at random), miss the TLB far less;
// - every thread allocates from the one arena: glibc would give each worker thread an arena of its
//   own, fresh memory faulted in page by page, while the main arena holds what earlier phases freed
//   (the split records' fit took nearly all its page faults on its second thread).
std::atomic<bool> huge_page_blocks{false};

// glibc's default mmap threshold, trim threshold and top pad alike (mallopt(3)), which a process that serves
// after building goes back to. The mmap threshold stays fixed there instead of adapting as it would: for a
// server every block of 128 KiB or more is its own mapping, returned when freed.
constexpr int kGlibcDefaultBytes = 128 * 1024;

#if defined(__GLIBC__) && defined(MADV_HUGEPAGE)
// Grows the heap by its new pad now and asks for 2 MiB pages on it.
void advise_heap_pad() {
  void* probe = std::malloc(kHugePage / 2);  // more than the heap's spare top: glibc grows it by this + the pad
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(probe) + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t end = reinterpret_cast<uintptr_t>(sbrk(0)) & ~(kHugePage - 1);
  std::free(probe);  // stays in the heap: it is never trimmed
  if (probe && end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // advice only
}
#endif

}  // namespace

BuildMemoryTuning::BuildMemoryTuning(AfterBuild after) : after_(after) {
  huge_page_blocks.store(true, std::memory_order_relaxed);
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, int(kHugePage));
  mallopt(M_TRIM_THRESHOLD, INT_MAX);
  mallopt(M_TOP_PAD, 64 << 20);
  // The pad on huge pages cannot be handed back as it came, and the arena limit not at all: only a
  // process that exits after its build takes them.
  if (after_ == AfterBuild::kExit) {
    mallopt(M_ARENA_MAX, 1);
#if defined(MADV_HUGEPAGE)
    advise_heap_pad();
#endif
  }
#endif
}

BuildMemoryTuning::~BuildMemoryTuning() {
  huge_page_blocks.store(false, std::memory_order_relaxed);
  if (after_ == AfterBuild::kExit) return;  // the process ends: nothing to give back
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, kGlibcDefaultBytes);
  mallopt(M_TRIM_THRESHOLD, kGlibcDefaultBytes);
  mallopt(M_TOP_PAD, kGlibcDefaultBytes);
  malloc_trim(0);  // what the build's phases kept for each other
#endif
}

bool large_blocks_on_huge_pages() { return huge_page_blocks.load(std::memory_order_relaxed); }

}  // namespace pms::app
