// Freed huge-page blocks kept for the next request of the same size. glibc maps a block of several MB
// afresh for every request and unmaps it when freed, so a fresh mesh faulted in (and the kernel
// cleared) new 2 MiB pages for its per-slot arrays each time, even right after an identical mesh was
// freed. Kept here, the next mesh over the same hierarchy finds them mapped and warm. Bounded: a few
// blocks and kKeptBytes in all, the oldest freed first, so a process holds at most that much it does
// not use.
#include <cstdlib>
#include <mutex>

#include "common/huge_pages.h"

namespace pms {
namespace {

constexpr size_t kKeptBytes = size_t(64) << 20;
constexpr int kKeptBlocks = 8;

struct Kept {
  void* block = nullptr;
  size_t bytes = 0;
};

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

void* take_recycled_block(size_t bytes) {
  RecycledBlocks& r = recycled();
  const std::lock_guard lock(r.mutex);
  for (int i = 0; i < r.count; ++i) {
    if (r.kept[i].bytes != bytes) continue;
    void* block = r.kept[i].block;
    r.remove(i);
    return block;
  }
  return nullptr;
}

void recycle_block(void* block, size_t bytes) {
  if (bytes > kKeptBytes) return std::free(block);
  RecycledBlocks& r = recycled();
  const std::lock_guard lock(r.mutex);
  while (r.count > 0 && (r.count == kKeptBlocks || r.bytes + bytes > kKeptBytes)) {
    std::free(r.kept[r.count - 1].block);
    r.remove(r.count - 1);
  }
  for (int j = r.count; j > 0; --j) r.kept[j] = r.kept[j - 1];
  r.kept[0] = {block, bytes};
  ++r.count;
  r.bytes += bytes;
}

}  // namespace pms
