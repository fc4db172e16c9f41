// Vertex ids of the view-dependent progressive mesh (kim-lee-kobbelt 2005 §4): what every layer and both
// ends of every streaming mode name a vertex by.
#pragma once
#include <bit>
#include <cstdint>
#include <string>

namespace pms {

constexpr uint32_t kNone = UINT32_MAX;

// <tree-id, node-id> (docs/internals.md, "Vertex ids"): tree = base-mesh vertex index, node = heap index with an
// implicit leading 1 (root 1, children 2n and 2n+1). Parent and children need no transmission.
struct VertexId {
  uint32_t tree = 0;
  uint64_t node = 1;

  VertexId parent() const { return {tree, node >> 1}; }
  VertexId child(int which) const { return {tree, (node << 1) | uint64_t(which)}; }
  int depth() const { return 63 - std::countl_zero(node); }
  bool is_root() const { return node == 1; }
  friend bool operator==(VertexId, VertexId) = default;
};

// ActiveAncestor by right shift (kim-lee-kobbelt §4): the ancestor of `v` at `depth`.
inline VertexId ancestor_at_depth(VertexId v, int depth) { return {v.tree, v.node >> (v.depth() - depth)}; }

inline bool is_ancestor_or_self(VertexId a, VertexId b) {
  if (a.tree != b.tree) return false;
  const int d = b.depth() - a.depth();
  return d >= 0 && (b.node >> d) == a.node;
}

// "No vertex" for optional ids such as a missing fundamental cut vertex: node-id 0 never occurs,
// every real id carries the implicit leading 1.
constexpr VertexId kNoVertex{0, 0};
inline bool is_vertex(VertexId v) { return v.node != 0; }
std::string to_string(VertexId v);  // "<tree,node>"

}  // namespace pms
