// How the engine's per-slot arrays (SelectiveMesh records, the adaptation loop's slots; slot_array.h)
// grow. Touching a new page is what costs (docs/internals.md, "Fresh meshes and memory"): while the
// known range is small the arrays double on the ordinary heap (blocks a later mesh reuses); past that
// the whole known range is taken at once (address space, on huge pages), so growing copies nothing more
// and memory is touched only where slots are written.
#pragma once
#include <algorithm>
#include <cstddef>

#include "common/huge_pages.h"

namespace pms {

constexpr size_t kSmallSlotBytes = size_t(64) << 10;

// The capacity to reserve for slots [0, end) of `known`, given the current capacity.
inline size_t slot_capacity(size_t end, size_t capacity, size_t known, size_t bytes_per_slot) {
  if (end <= capacity) return capacity;
  if (known * bytes_per_slot <= kSmallSlotBytes)
    return std::max(end, std::min(2 * capacity, kSmallSlotBytes / bytes_per_slot));
  return std::max(known, 2 * capacity);
}

}  // namespace pms
