// How the engine's per-slot arrays (SelectiveMesh records, the adaptation loop's slots) grow: with the
// highest slot in use, not with the model, so a fresh mesh pays for what it refines. Touching a new page
// is what costs (docs/internals.md, "Against SrMesh; fresh meshes"): small arrays double on the ordinary
// heap (below malloc's mmap threshold: blocks a later mesh reuses); past that the whole known range is
// reserved at once (address space only, on huge pages when it is big enough), so growing copies nothing
// more and memory is touched only where slots are written.
#pragma once
#include <algorithm>
#include <cstddef>

#include "common/huge_pages.h"

namespace pms {

constexpr size_t kSmallSlotBytes = size_t(64) << 10;

// The capacity to reserve for slots [0, end) of `known`, given the current capacity.
inline size_t slot_capacity(size_t end, size_t capacity, size_t known, size_t bytes_per_slot) {
  if (end <= capacity) return capacity;
  const size_t doubled = std::max(end, 2 * capacity);
  if (doubled * bytes_per_slot <= kSmallSlotBytes) return doubled;
  return std::max(known, 2 * capacity);
}

// The size to initialise for slots [0, end), once slot_capacity's capacity is reserved. While the
// array doubles, a few slots ahead save calls; once the whole known range is reserved nothing moves
// any more, and every slot initialised past `end` only writes (and faults in) memory no slot uses yet.
inline size_t slot_size(size_t end, size_t size, size_t capacity, size_t known) {
  if (capacity >= known) return std::max(end, size);
  return std::min(known, std::max(end, 2 * size));
}

}  // namespace pms
