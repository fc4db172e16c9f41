// LevelNeighbours and CornerCandidates (multilevel/level_neighbours.h).
#include "multilevel/level_neighbours.h"

#include <algorithm>

namespace pms {

void LevelNeighbours::reset(uint32_t vertices) {
  slot_.assign(vertices, kNone);
  lists_.clear();
}

void LevelNeighbours::add_edge(uint32_t a, uint32_t b) {
  if (slot_[a] == kNone) {
    slot_[a] = uint32_t(lists_.size());
    lists_.emplace_back();
  }
  std::vector<uint32_t>& list = lists_[slot_[a]];
  if (a == b || list.size() >= kMaxNeighbours || std::find(list.begin(), list.end(), b) != list.end()) return;
  list.push_back(b);
}

void LevelNeighbours::add_triangle(const uint32_t corner[3]) {
  for (int k = 0; k < 3; ++k) {
    add_edge(corner[k], corner[(k + 1) % 3]);
    add_edge(corner[(k + 1) % 3], corner[k]);
  }
}

void CornerCandidates::add(uint32_t v, VertexMarks& listed) {
  if (size_ >= kCandidates || v == LevelNeighbours::kNone || listed.has(v)) return;
  listed.add(v);
  list_[size_++] = v;
}

std::span<const uint32_t> CornerCandidates::build(const LevelNeighbours& mesh, std::span<const uint32_t> decided,
                                                  std::span<const uint32_t> first, uint32_t cursor,
                                                  VertexMarks& listed, VertexMarks& beside) {
  size_ = 0;
  listed.clear();
  for (uint32_t v : decided) listed.add(v);
  for (uint32_t v : first) add(v, listed);
  add(cursor, listed);
  if (decided.size() == 2) {
    beside.clear();
    for (uint32_t v : mesh.of(decided[0])) beside.add(v);
    for (uint32_t v : mesh.of(decided[1]))
      if (beside.has(v)) add(v, listed);
  }
  if (!decided.empty())
    for (uint32_t v : mesh.of(decided.back())) add(v, listed);
  if (decided.size() == 2)
    for (uint32_t v : mesh.of(decided[0])) add(v, listed);
  for (uint32_t i = 0; i < recent_size_; ++i) add(recent_[i], listed);
  return {list_.data(), size_};
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
