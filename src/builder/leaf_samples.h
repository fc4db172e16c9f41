// Per current vertex of the collapsing mesh: up to kMax input vertices (leaves) spread over the
// subtree it carries, and the subtree's leaf count. Hoppe 1997 §4.3 measures a node's deviation at
// points of the input surface below it; drawing a parent's samples from its children's, in proportion
// to their sizes, spares a walk of every subtree (n * depth cache misses on big meshes).
//
// Every set lives in one arena. A merge appends the new set and leaves the two old ones as garbage,
// which is collected once it outgrows the live sets. The live sets never hold more than the n leaves
// (a set holds at most its subtree's leaves), so memory stays a few words per input vertex however
// large kMax is: 128 samples per set cost no more than 8 did with fixed-size slots.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/huge_pages.h"

namespace pms {

class LeafSamples {
 public:
  // Beyond ~128 samples a node's estimated deviation stops changing (dragon: the same faces at τ = 1 px
  // for 128 and 255).
  static constexpr uint32_t kMax = 128;

  // Vertex v carries leaf v alone.
  explicit LeafSamples(uint32_t vertex_count);

  std::span<const uint32_t> of(uint32_t v) const { return {&arena_[offset_[v]], count_[v]}; }
  uint32_t leaf_count(uint32_t v) const { return leaf_count_[v]; }

  // Vertex t was collapsed into u: u now carries both subtrees. Keeps all samples while they fit, else
  // takes from each side in proportion to its leaves (at least one each), u's first.
  void merge(uint32_t t, uint32_t u);

  // Vertices renumbered: v becomes new_index[v], or is dropped if that is UINT32_MAX.
  void compact(const std::vector<uint32_t>& new_index);

 private:
  void collect_garbage();

  BigVector<uint32_t> arena_;
  BigVector<size_t> offset_;  // per vertex: where its set starts in arena_
  BigVector<uint8_t> count_;  // per vertex: samples in its set (0: collapsed away)
  BigVector<uint32_t> leaf_count_;
  size_t live_ = 0;  // samples in the sets of live vertices
};

}  // namespace pms
