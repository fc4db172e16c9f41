#include "builder/leaf_samples.h"

#include <algorithm>
#include <limits>

namespace pms {

static_assert(LeafSamples::kMax >= 2 && LeafSamples::kMax <= std::numeric_limits<uint8_t>::max());

namespace {

// Garbage is collected past twice the live samples; one merge appends at most 2 kMax before the check.
// Reserving that much means the arena itself is never copied by growing.
size_t capacity_for(size_t live) { return 2 * live + 1024 + 2 * LeafSamples::kMax; }

}  // namespace

LeafSamples::LeafSamples(uint32_t vertex_count)
    : arena_(vertex_count),
      offset_(vertex_count),
      count_(vertex_count, 1),
      leaf_count_(vertex_count, 1),
      live_(vertex_count) {
  for (uint32_t v = 0; v < vertex_count; ++v) {
    arena_[v] = v;
    offset_[v] = v;
  }
  arena_.reserve(capacity_for(live_));
}

void LeafSamples::merge(uint32_t t, uint32_t u) {
  const uint32_t have_t = count_[t], have_u = count_[u];
  const uint64_t total = uint64_t(leaf_count_[t]) + leaf_count_[u];
  uint32_t from_t =
      have_t + have_u <= kMax ? have_t : std::clamp<uint32_t>(uint32_t(kMax * leaf_count_[t] / total), 1, kMax - 1);
  from_t = std::min(from_t, have_t);
  const uint32_t from_u = std::min(have_u, kMax - from_t);
  leaf_count_[u] = uint32_t(std::min<uint64_t>(total, std::numeric_limits<uint32_t>::max()));
  live_ -= have_t + have_u;
  live_ += from_t + from_u;
  count_[t] = 0;
  count_[u] = uint8_t(from_t + from_u);
  if (offset_[u] + have_u == arena_.size() && from_u == have_u) {  // u's set ends the arena: grow it in place
    arena_.insert(arena_.end(), &arena_[offset_[t]], &arena_[offset_[t]] + from_t);
  } else {
    const size_t start = arena_.size();
    // Copy through indices: inserting may reallocate under a pointer into the arena itself.
    for (uint32_t i = 0; i < from_u; ++i) arena_.push_back(arena_[offset_[u] + i]);
    for (uint32_t i = 0; i < from_t; ++i) arena_.push_back(arena_[offset_[t] + i]);
    offset_[u] = start;
  }
  if (arena_.size() > 2 * live_ + 1024) collect_garbage();  // within capacity_for(live_): no copy
}

void LeafSamples::collect_garbage() {
  BigVector<uint32_t> packed;
  packed.reserve(capacity_for(live_));
  for (size_t v = 0; v < offset_.size(); ++v) {
    const size_t start = packed.size();
    packed.insert(packed.end(), arena_.begin() + ptrdiff_t(offset_[v]),
                  arena_.begin() + ptrdiff_t(offset_[v] + count_[v]));
    offset_[v] = start;
  }
  arena_.swap(packed);
}

void LeafSamples::compact(const std::vector<uint32_t>& new_index) {
  uint32_t live = 0;
  for (uint32_t v = 0; v < new_index.size(); ++v) {
    if (new_index[v] == UINT32_MAX) continue;
    offset_[live] = offset_[v];
    count_[live] = count_[v];
    leaf_count_[live] = leaf_count_[v];
    ++live;
  }
  offset_.resize(live);
  count_.resize(live);
  leaf_count_.resize(live);
  collect_garbage();  // the dropped vertices' sets are garbage now, and the arena shrinks with the mesh
}

}  // namespace pms
