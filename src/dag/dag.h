// The DAG of vertex-split / edge-collapse operations (Zheng & Chan 2005, 2006 §3) over a model's vertex
// hierarchy, with the truly selective fundamental cut vertices of Kim & Lee 2001: one node per internal
// hierarchy node, an edge a -> b when b's split needs a split (and so a's collapse needs b collapsed).
// Built once per model and shared by every cut (dag/cut.h); docs/internals.md ("The DAG of
// operations") says which edges there are and why each is needed.
// Shared with the browser build: single-threaded, no std::ranges algorithms, std::format or coroutines.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "spm/criteria.h"
#include "spm/hierarchy.h"

namespace pms {

struct DagStats {
  uint32_t nodes = 0;
  uint64_t parent_edges = 0;      // hierarchy parent -> child (v_s must be active to split)
  uint64_t dependency_edges = 0;  // deepest common ancestor of v̂_l, v̂_r -> node (v_l != v_r)
  // Candidates left out because another path already implies them (transitive reduction).
  uint64_t redundant_ancestor = 0;    // the common ancestor is an ancestor of the node itself
  uint64_t redundant_dependency = 0;  // implied by the parent's requirements
  uint64_t redundant_parent = 0;      // implied by the dependency's requirements
  uint32_t max_children = 0;          // largest out-degree
  double seconds = 0;                 // build time
  double edges_per_node() const { return nodes ? double(parent_edges + dependency_edges) / nodes : 0; }
};

class Dag {
 public:
  // Counters of a cut must hold any node's out-degree (DagCut's side table has 16 bits).
  static constexpr uint32_t kMaxChildren = 65535;

  // `positions`: 3 floats per model node that ERROR-EVALUATE reads (e.g. the wire grid's snapped ones);
  // empty = the model's own. pms::Error for a model with inconsistent links or a node with more than
  // kMaxChildren dependents.
  explicit Dag(const ModelData& model, std::span<const float> positions = {});

  uint32_t size() const { return uint32_t(model_node_.size()); }
  uint32_t model_node(uint32_t n) const { return model_node_[n]; }
  uint32_t node_of(uint32_t model_node) const { return node_of_[model_node]; }  // kNone for leaves
  // Nodes that must be split before n is (in-edges) and nodes whose split needs n (out-edges).
  std::span<const uint32_t> parents(uint32_t n) const {
    return {in_edges_.data() + in_begin_[n], in_edges_.data() + in_begin_[n + 1]};
  }
  std::span<const uint32_t> children(uint32_t n) const {
    return {out_edges_.data() + out_begin_[n], out_edges_.data() + out_begin_[n + 1]};
  }
  // The hierarchy around n, as DAG nodes: its parent (kNone for a root) and its two children (kNone
  // for a leaf child). A reduced DAG may lack the parent edge, but a split still needs v_s active.
  uint32_t hierarchy_parent(uint32_t n) const { return hierarchy_parent_[n]; }
  uint32_t hierarchy_child(uint32_t n, int k) const { return hierarchy_child_[2 * size_t(n) + uint32_t(k)]; }
  // Triangles n's split adds (f_l and/or f_r) and its collapse removes.
  uint32_t faces(uint32_t n) const { return faces_[n]; }
  const NodeCriteria& criteria(uint32_t n) const { return criteria_[n]; }
  // On their way to the cache: what parents(), children(), the hierarchy and faces() read of n first, and
  // then (once those are in) its edge lists. Loading a cut walks thousands of scattered nodes.
  void prefetch_links(uint32_t n) const {
    __builtin_prefetch(&in_begin_[n]);
    __builtin_prefetch(&out_begin_[n]);
    __builtin_prefetch(&hierarchy_parent_[n]);
    __builtin_prefetch(&hierarchy_child_[2 * size_t(n)]);
    __builtin_prefetch(&faces_[n]);
  }
  void prefetch_edges(uint32_t n) const {
    __builtin_prefetch(in_edges_.data() + in_begin_[n]);  // may be the end: a prefetch does not fault
    __builtin_prefetch(out_edges_.data() + out_begin_[n]);
  }
  uint64_t base_faces() const { return base_faces_; }
  std::span<const uint32_t> roots() const { return roots_; }  // nodes without a hierarchy parent
  const DagStats& stats() const { return stats_; }
  // The centre of the nodes' bounding box: constant-time's reference point for how the eye's distance to
  // the model changes between frames (DagCut::watch()).
  const float* centre() const { return centre_; }
  size_t memory_bytes() const;
  // A number no other Dag built in this process has: a per-thread cache keyed by it and the address never
  // takes a Dag built where a freed one was for the old one (dag/compact.h).
  uint64_t serial() const { return serial_; }

 private:
  std::vector<uint32_t> model_node_, node_of_, hierarchy_parent_, roots_;
  std::vector<uint32_t> hierarchy_child_;  // 2 per node
  std::vector<uint32_t> in_begin_, in_edges_, out_begin_, out_edges_;
  std::vector<uint8_t> faces_;
  std::vector<NodeCriteria> criteria_;
  uint64_t base_faces_ = 0;
  uint64_t serial_ = 0;
  float centre_[3] = {0, 0, 0};
  DagStats stats_;
};

}  // namespace pms
