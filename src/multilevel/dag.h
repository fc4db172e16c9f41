// The DAG of collapses of a progressive multilevel mesh (gueziec, taubin, horn, lazarus 1999, "Local
// refinement", Fig. 14): one node per vertex below the top level (its collapse onto its representative and
// the vertex split that undoes it), and edges for the order the collapses need, so that a region can be
// refined with a consistent subset of vertex splits (Fig. 15; multilevel/local.h).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "multilevel/mesh.h"

namespace pms {

// Nodes are the vertices [top_vertices, vertices): a multilevel mesh numbers vertices by decreasing level,
// and the collapses are replayed from the last vertex to the first, so every prerequisite of a split has a
// lower number than the split's vertex (the DAG is acyclic by construction and increasing vertex number is
// a topological order).
struct MultilevelDag {
  static constexpr uint32_t kNoRemover = 0xFFFFFFFFu;

  uint32_t vertices = 0, top_vertices = 0;
  // CSR per vertex (empty rows for the top level): prerequisites of v are the vertices that must be split
  // before v can be (the paper's edges V -> I read backwards: collapsing V first needs I collapsed), and
  // dependents of v the vertices whose splits need v split.
  std::vector<uint32_t> prerequisite_offsets, prerequisites;
  std::vector<uint32_t> dependent_offsets, dependents;
  // Per triangle: the vertex whose collapse removed it in the replay, so it is in the mesh exactly when that
  // vertex is; kNoRemover for the top level's triangles (always there) and for those no collapse removed
  // (degenerate in the file, or dropped at a level's end without degenerating), which are there only when
  // the whole LOD of their level is.
  std::vector<uint32_t> remover;
  // Per node, the radius of its collapse's star around the vertex: the screen-size rule's extent.
  std::vector<float> radius;
  // Per node, 4 floats: the normal cone of the triangles its split changes (those around the vertex and its
  // representative before the collapse), as Hoppe 1997 §4.2's back-face test reads it: the unit axis and
  // sin² of the half-angle; above 1 when the half-angle reaches 90° (the star is never back-facing).
  std::vector<float> cone;

  std::span<const uint32_t> prerequisites_of(uint32_t v) const {
    return {prerequisites.data() + prerequisite_offsets[v], prerequisites.data() + prerequisite_offsets[v + 1]};
  }
  std::span<const uint32_t> dependents_of(uint32_t v) const {
    return {dependents.data() + dependent_offsets[v], dependents.data() + dependent_offsets[v + 1]};
  }
  bool is_node(uint32_t v) const { return v >= top_vertices && v < vertices; }
  uint64_t edge_count() const { return prerequisites.size(); }
  uint64_t memory_bytes() const;
};

// Replays the collapses of `mesh` (validated) from its last vertex to its first: vertex v goes onto its
// representative (or, without one, vanishes with its triangles), the triangles that degenerate go with it,
// and a level's remaining triangles go at its end. The edges of collapse v are the paper's, from the star
// of the collapsed edge (v and its representative, and their neighbours): each star vertex a previous
// collapse produced (the latest collapse onto it) must be collapsed before v, so its split needs v's; and
// v's own neighbours must be there for v's triangles to be, so v's split needs theirs. For a mesh from
// assemble_multilevel (merged or not) that order makes the builder's collapses in an equivalent order,
// but for the vertices no coarser triangle needs, which vanish with triangles of their own level only.
MultilevelDag build_multilevel_dag(const MultilevelMesh& mesh);

}  // namespace pms
