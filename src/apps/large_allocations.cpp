// The pmstream binary's operator new: while a build runs (apps/build_pipeline.h, BuildMemoryTuning),
// blocks of 2 MiB and more are aligned to 2 MiB and asked for transparent huge pages. glibc hands blocks
// from 32 MiB up straight to mmap, on 4 KiB pages, so every std::vector of a large build (candidates,
// info, forests: hundreds of MB read in cost order, i.e. at random) missed the TLB on nearly every read;
// under a hypervisor each miss is a nested page walk and each first touch a fault of several
// microseconds. Arrays the code knows are big already ask for themselves (common/huge_pages.h); this
// covers the rest, from every layer, without changing their types.
//
// An operator new is the whole program's, so it is switched at run time: `serve`, `stream` and a demo's
// server and client get malloc's blocks as they are, since a session's buffers come and go and a 2 MiB
// page for each would only raise the server's resident size.
//
// Linked into the executable only (tests and fuzzers keep the standard operators), and left out
// under sanitizers, which bring their own.
#include <cstdlib>
#include <new>

#include "apps/build_memory.h"
#include "common/huge_pages.h"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define PMS_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define PMS_SANITIZED 1
#endif
#endif

#if defined(__linux__) && !defined(PMS_SANITIZED)

namespace {

void* allocate(size_t bytes) {
  if (bytes < pms::kHugePage || !pms::app::large_blocks_on_huge_pages()) return std::malloc(bytes == 0 ? 1 : bytes);
  return pms::allocate_on_huge_pages(bytes);
}

void* allocate_or_throw(size_t bytes) {
  for (;;) {
    if (void* p = allocate(bytes)) return p;
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

}  // namespace

// Both kinds of block are malloc's, so free releases either; the aligned and sized forms the
// library provides forward to these or to free as well.
void* operator new(size_t bytes) { return allocate_or_throw(bytes); }
void* operator new[](size_t bytes) { return allocate_or_throw(bytes); }
void* operator new(size_t bytes, const std::nothrow_t&) noexcept { return allocate(bytes); }
void* operator new[](size_t bytes, const std::nothrow_t&) noexcept { return allocate(bytes); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
void operator delete[](void* p, size_t) noexcept { std::free(p); }

#endif
