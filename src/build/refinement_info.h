// Hoppe 1997 §4 refinement info, computed while collapsing: bounding-sphere radius over the input
// faces below a node, normal cone of those faces, and the deviation space (mu, delta) of the
// node's leaf positions against the surface around it right after its collapse.
#pragma once
#include <cstdint>
#include <vector>

#include "build/collapse_mesh.h"
#include "io/mesh.h"
#include "pm/pm.h"

namespace pms {

class RefinementInfoBuilder {
 public:
  // Leaves get their 1-ring bounds; `max_nodes` = leaves + the most collapses that can follow.
  RefinementInfoBuilder(const Mesh& mesh, size_t max_nodes);

  float scale() const { return scale_; }

  // Node s was made by collapsing node t_node into u_node: joins their leaf lists. Sequential.
  void merge_leaves(uint32_t s, uint32_t t_node, uint32_t u_node);
  // Bounds of s; the surviving vertex u of `mesh` carries s. Merged from the children's *decoded*
  // values so every parent contains its children exactly as every consumer will see them.
  // Reads the mesh only and writes only node s: independent collapses may run in parallel.
  void compute(uint32_t s, uint32_t t_node, uint32_t u_node, const CollapseMesh& mesh, uint32_t u);

  const RefineInfo& info(uint32_t node) const { return info_[node]; }
  std::vector<RefineInfo> take() { return std::move(info_); }

 private:
  const float* leaf_position(uint32_t leaf) const { return &positions_[3 * size_t(leaf)]; }
  void deviation(uint32_t s, const CollapseMesh& mesh, uint32_t u, const float axis[3], float& mu, float& delta) const;

  const std::vector<float>& positions_;
  float scale_ = 1;
  std::vector<RefineInfo> info_;
  std::vector<uint32_t> survivor_;   // per node: leaf carrying its position
  // Leaves below each node as linked lists (head/tail per node, next per leaf): merging is O(1).
  std::vector<uint32_t> leaf_head_, leaf_tail_, leaf_next_, leaf_count_;
};

}  // namespace pms
