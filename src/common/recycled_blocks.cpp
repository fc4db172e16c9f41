// Freed huge-page blocks kept for the next request of the same size and kind. glibc maps a block of
// several MB afresh for every request and unmaps it when freed, so without this cache a fresh mesh faults
// in (and the kernel clears) new 2 MiB pages for its arrays each time, even right after an identical mesh
// was freed. Kept here, the next mesh over the same hierarchy finds them mapped and warm. Bounded: a few
// blocks and kKeptBytes in all, the oldest freed first, so a process holds at most that much it does
// not use.
#include <cstdlib>
#include <cstring>
#include <mutex>

#include "common/huge_pages.h"

namespace pms {
namespace {

constexpr size_t kKeptBytes = size_t(128) << 20;
constexpr int kKeptBlocks = 8;

struct Kept {
  void* block = nullptr;
  size_t bytes = 0;
  int kind = 0;
};

void release(const Kept& k) {
  if (k.kind == 0) std::free(k.block);
  else unmap_zeroed(k.block, k.bytes);
}

struct RecycledBlocks {
  std::mutex mutex;
  Kept kept[kKeptBlocks];  // the newest first
  int count = 0;
  size_t bytes = 0;

  void remove(int i) {
    bytes -= kept[i].bytes;
    for (int j = i + 1; j < count; ++j) kept[j - 1] = kept[j];
    --count;
  }
};

RecycledBlocks& recycled() {
  static RecycledBlocks& blocks = *new RecycledBlocks;  // never destroyed: arrays may be freed at exit
  return blocks;
}

}  // namespace

void* take_recycled_block(size_t bytes, int kind) {
  RecycledBlocks& r = recycled();
  const std::lock_guard lock(r.mutex);
  for (int i = 0; i < r.count; ++i) {
    if (r.kept[i].bytes != bytes || r.kept[i].kind != kind) continue;
    void* block = r.kept[i].block;
    r.remove(i);
    return block;
  }
  return nullptr;
}

void recycle_block(void* block, size_t bytes, int kind) {
  if (bytes > kKeptBytes) return release({block, bytes, kind});
  RecycledBlocks& r = recycled();
  const std::lock_guard lock(r.mutex);
  while (r.count > 0 && (r.count == kKeptBlocks || r.bytes + bytes > kKeptBytes)) {
    release(r.kept[r.count - 1]);
    r.remove(r.count - 1);
  }
  for (int j = r.count; j > 0; --j) r.kept[j] = r.kept[j - 1];
  r.kept[0] = {block, bytes, kind};
  ++r.count;
  r.bytes += bytes;
}

#if defined(__linux__)
// A fresh anonymous mapping is zero and costs nothing until written; its unaligned ends are returned.
void* map_zeroed(size_t bytes) {
  const size_t span = bytes + kHugePage;
  if (span < bytes) return nullptr;
  void* p = mmap(nullptr, span, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) return nullptr;
  const uintptr_t start = reinterpret_cast<uintptr_t>(p), begin = (start + kHugePage - 1) & ~(kHugePage - 1);
  if (begin > start) munmap(p, begin - start);
  if (const size_t tail = start + span - (begin + bytes); tail > 0)
    munmap(reinterpret_cast<void*>(begin + bytes), tail);
#if defined(MADV_HUGEPAGE)
  madvise(reinterpret_cast<void*>(begin), bytes, MADV_HUGEPAGE);  // advice only
#endif
  return reinterpret_cast<void*>(begin);
}

void unmap_zeroed(void* block, size_t bytes) { munmap(block, bytes); }
#else
void* map_zeroed(size_t bytes) {
  void* p = std::aligned_alloc(kHugePage, bytes);
  if (p) std::memset(p, 0, bytes);
  return p;
}

void unmap_zeroed(void* block, size_t) { std::free(block); }
#endif

}  // namespace pms
