// The view-dependent progressive-mesh model (kim-lee-kobbelt 2005 §4, §6; Hoppe 1997 §4): the packed vertex
// hierarchy every mode shares, owned (Hierarchy) or viewed in place (ModelData, e.g. over a mapped .pms).
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "spm/refine_info.h"
#include "spm/vertex_id.h"

namespace pms {

// The hierarchy, owned. Nodes are packed breadth-first by depth (parent index < child index):
// indices [0, root_count) are the roots = base-mesh vertices, tree-id = index.
// Internal node n has children first_child[n] (v_t, node-id 2k) and first_child[n] + 1
// (v_u, node-id 2k+1). v_u keeps the parent's position (half-edge collapse v_t -> v_u), so a
// split only introduces v_t's position.
struct Hierarchy {
  uint32_t root_count = 0;
  std::vector<uint32_t> base_faces;   // 3 root indices per face, CCW
  std::vector<uint32_t> parent;       // per node; kNone for roots
  std::vector<uint32_t> first_child;  // per node; kNone for leaves
  std::vector<float> position;        // 3 per node
  std::vector<uint32_t> cut_left;     // per node: leaf index of v̂_l; kNone for leaves or no left face
  std::vector<uint32_t> cut_right;    // per node: leaf index of v̂_r; kNone for leaves or no right face
  std::vector<RefineInfo> refine;     // per node
  std::vector<uint32_t> leaf_vertex;  // per node: vertex index in the cleaned input; kNone if internal
  std::vector<uint32_t> split_order;  // internal nodes in PM order (reverse of collapse order)
  std::vector<float> normals;         // optional: 3 per node (internal nodes: survivor leaf's)
  std::vector<uint8_t> colors;        // optional: 4 per node
  float bbox_min[3] = {0, 0, 0};
  float bbox_max[3] = {0, 0, 0};
  float scale = 1;  // bounding-box diagonal; refinement info is relative to it

  // Derived from the structure (not stored in the file): ids per node.
  std::vector<uint32_t> tree_id;
  std::vector<uint64_t> node_id;

  size_t node_count() const { return parent.size(); }
  size_t leaf_count() const;
  bool is_leaf(uint32_t n) const { return first_child[n] == kNone; }
  VertexId id(uint32_t n) const { return {tree_id[n], node_id[n]}; }
  void compute_ids();                // fills tree_id/node_id from parent/first_child
  uint32_t find(VertexId id) const;  // node index by walking from the root; kNone if absent
};

// Bits needed to write ids, as reported by build/info (kim-lee-kobbelt §6.2 Table 1).
uint32_t tree_id_bits(uint64_t root_count);
uint32_t max_depth(const Hierarchy& h);

// A model as read-only arrays, over a Hierarchy in memory or a memory-mapped .pms file.
struct ModelData {
  uint32_t root_count = 0;
  std::span<const uint32_t> base_faces;
  std::span<const uint32_t> parent, first_child;
  std::span<const float> position;
  std::span<const uint32_t> cut_left, cut_right;
  std::span<const RefineInfo> refine;
  std::span<const uint32_t> leaf_vertex;
  std::span<const uint32_t> split_order;
  std::span<const float> normals;
  std::span<const uint8_t> colors;
  std::span<const uint32_t> tree_id;
  std::span<const uint64_t> node_id;
  const float* bbox_min = nullptr;
  const float* bbox_max = nullptr;
  float scale = 1;

  size_t node_count() const { return parent.size(); }
  bool is_leaf(uint32_t n) const { return first_child[n] == kNone; }
  VertexId id(uint32_t n) const { return {tree_id[n], node_id[n]}; }
  uint32_t find(VertexId id) const;
};

ModelData model_of(const Hierarchy& h);

// pms::Error when a hand-made model's node arrays are shorter than its node count (a model of a validated
// .pms file never is): what reads a model at node indices checks it first.
void check_node_arrays(const ModelData& model);

}  // namespace pms
