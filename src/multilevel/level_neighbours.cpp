// LevelNeighbours and CornerCandidates (multilevel/level_neighbours.h).
#include "multilevel/level_neighbours.h"

#include <algorithm>

namespace pms {

void LevelNeighbours::add_edge(uint32_t a, uint32_t b) {
  if (a >= block_.size()) block_.resize(std::clamp<size_t>(2 * block_.size(), a + 1, std::max(a + 1, vertices_)));
  Block& block = block_[a];
  block.named = 1;
  const auto end = block.neighbour.begin() + block.count;
  if (a == b || block.count >= kMaxNeighbours || std::find(block.neighbour.begin(), end, b) != end) return;
  *end = b;
  ++block.count;
}

void LevelNeighbours::add_triangle(const uint32_t corner[3]) {
  for (int k = 0; k < 3; ++k) {
    add_edge(corner[k], corner[(k + 1) % 3]);
    add_edge(corner[(k + 1) % 3], corner[k]);
  }
}

bool CornerCandidates::add(uint32_t v, std::span<const uint32_t> decided, const Until& until) {
  const std::span<const uint32_t> listed = list();
  if (size_ < kCandidates && v != LevelNeighbours::kNone && std::find(decided.begin(), decided.end(), v) == decided.end() &&
      std::find(listed.begin(), listed.end(), v) == listed.end()) {
    list_[size_++] = v;
    if (v == until.vertex) return true;
  }
  return size_ >= kCandidates || size_ > until.place;
}

std::span<const uint32_t> CornerCandidates::build(const LevelNeighbours& mesh, std::span<const uint32_t> decided,
                                                  std::span<const uint32_t> first, uint32_t cursor, Until until) {
  size_ = 0;
  const auto done = [&] { return list(); };
  for (uint32_t v : first)
    if (add(v, decided, until)) return done();
  if (add(cursor, decided, until)) return done();
  if (decided.size() == 2)
    for (uint32_t v : mesh.of(decided[1]))
      if (mesh.adjacent(decided[0], v) && add(v, decided, until)) return done();
  if (!decided.empty())
    for (uint32_t v : mesh.of(decided.back()))
      if (add(v, decided, until)) return done();
  if (decided.size() == 2)
    for (uint32_t v : mesh.of(decided[0]))
      if (add(v, decided, until)) return done();
  for (uint32_t i = 0; i < recent_size_; ++i)
    if (add(recent_[i], decided, until)) return done();
  return done();
}

void CornerCandidates::remember(const uint32_t corner[3]) {
  for (int k = 0; k < 3; ++k) {
    const uint32_t v = corner[k];
    uint32_t i = uint32_t(std::find(recent_.begin(), recent_.begin() + recent_size_, v) - recent_.begin());
    if (i == recent_size_) i = recent_size_ < kRecent ? recent_size_++ : kRecent - 1;
    std::move_backward(recent_.begin(), recent_.begin() + i, recent_.begin() + i + 1);
    recent_[0] = v;
  }
}

}  // namespace pms
