// Hoppe 1997 §4 refinement info, computed while collapsing: bounding-sphere radius over the input
// faces below a node, normal cone of those faces, and the deviation space (mu, delta) of the input
// surface below the node against the surface around it right after its collapse: the larger of the
// sampled leaves' residuals and each child's space grown by how far the collapse moved the surface
// (Deviation::bound), or the moved surface counted once beside the children's spaces (::estimate).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "builder/build.h"
#include "builder/collapse_mesh.h"
#include "builder/leaf_samples.h"
#include "io/mesh.h"
#include "spm/refine_info.h"

namespace pms {

class RefinementInfoBuilder {
 public:
  // Leaves get their 1-ring bounds (`connectivity`: the untouched CollapseMesh of `mesh`, for its
  // faces around each vertex); `max_nodes` = leaves + the most collapses that can follow.
  RefinementInfoBuilder(const Mesh& mesh, const CollapseMesh& connectivity, size_t max_nodes, Deviation deviation);

  float scale() const { return scale_; }

  // Node s was made by collapsing vertex t (node t_node) into vertex u (node u_node): u's leaf
  // samples become s's. Sequential.
  void merge_leaves(uint32_t s, uint32_t t_node, uint32_t u_node, uint32_t t, uint32_t u);
  // The leaf samples vertex v of the working mesh carries.
  std::span<const uint32_t> samples_of(uint32_t v) const { return samples_.of(v); }
  // Bounds of node s, made from t_node and u_node, merged from the children's *decoded* values so every
  // parent contains its children exactly as every consumer will see them. `corners`: the faces around
  // s's vertex right after its round, 3 leaves each (CapturedRound); `samples`: the leaf samples it
  // carried then. Reads those and earlier rounds' bounds and writes only node s: a round's collapses
  // may run in parallel, and while the next round collapses.
  void compute(uint32_t s, uint32_t t_node, uint32_t u_node, std::span<const uint32_t> corners,
               std::span<const uint32_t> samples);

  // Follows CollapseMesh::compact(): per-vertex arrays renumbered the same way.
  void compact(const std::vector<uint32_t>& new_index);

  const RefineInfo& info(uint32_t node) const { return info_[node]; }
  std::vector<RefineInfo> take() { return std::move(info_); }

 private:
  const float* leaf_position(uint32_t leaf) const { return &positions_[3 * size_t(leaf)]; }
  struct Fan;             // the faces around a vertex right after its collapse
  struct DeviationSpace;  // (mu, delta) about an axis, Hoppe 1997 §4.3
  Fan fan_of(std::span<const uint32_t> corners, uint32_t u_leaf) const;
  void add_leaf_samples(const Fan& fan, std::span<const uint32_t> samples, DeviationSpace& space) const;
  void add_moved_surface(const Fan& fan, uint32_t t_leaf, DeviationSpace& space) const;

  const std::vector<float>& positions_;
  Deviation deviation_;
  float scale_ = 1;
  std::vector<RefineInfo> info_;
  BigVector<uint32_t> survivor_;  // per node: leaf carrying its position
  LeafSamples samples_;           // per current vertex, leaves of its subtree (Hoppe's points)
};

}  // namespace pms
