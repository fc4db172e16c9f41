// Building a progressive multilevel mesh from edge collapses (gueziec et al. 1999, "From edge collapses to a
// progressive multilevel representation", Fig. 3-5), and merging its levels.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "io/mesh.h"
#include "multilevel/mesh.h"
#include "spm/hierarchy.h"

namespace pms {

// A directed (half-edge) collapse: `removed` (the paper's blue vertex) goes, `survivor` (red) stays where it
// is and becomes its representative. Vertex numbers are the input mesh's.
struct EdgeCollapse {
  uint32_t removed = 0;
  uint32_t survivor = 0;
};

// The builder's collapses in the order it made them (the reverse of split_order), in the numbering of
// the mesh it was given (Hierarchy::leaf_vertex): a node stands for the leaf its v_u children lead to.
std::vector<EdgeCollapse> collapses_of(const Hierarchy& hierarchy);
// The same over a model's arrays (e.g. a mapped .pms: the server derives a model's levels from it).
std::vector<EdgeCollapse> collapses_of(const ModelData& model);

// Per input vertex and triangle, the level the paper assigns (0 = finest): a collapse gets 1 + the highest
// level in its edge's star, which its two endpoints take; its blue vertex and the triangles it removes keep
// it; what is left at the end takes one more than the highest. Levels here are that minus one.
struct CollapseLevels {
  uint32_t level_count = 0;
  std::vector<uint32_t> vertex_level, triangle_level;
  std::vector<uint32_t> parent;  // per vertex: what it collapsed onto (kNoRepresentative if it survived)
  // Per collapse in sequence order (empty for clusterings): its blue vertex, and as CSR the blue vertices
  // of the earlier collapses that last touched a vertex of its edge's star. Any order that keeps these
  // (and children before parents) makes the builder's mesh at every step of every level.
  std::vector<uint32_t> collapse_removed, earlier_offsets, earlier;
};

// pms::Error when a collapse names a vertex out of range, already removed, or collapses onto itself.
CollapseLevels assign_levels(const Mesh& mesh, std::span<const EdgeCollapse> collapses);

// Which representatives assemble_multilevel stores.
enum class MultilevelRepresentatives {
  // Only those the discrete LODs need (the paper's minimum): vertex v of a triangle of level k with
  // level(v) < k needs its chain of parents until one of level >= k.
  discrete,
  // Also those a geomorph needs so that at t = 0 it is LOD k + 1 exactly: the chain continues through
  // vertices of level k until one of level > k (the paper's "more representatives ... than those required
  // strictly for discrete levels"). No triangle states them: multilevel/mesh.h, geomorph_representatives.
  geomorph,
};

// Sorts the mesh by decreasing level and keeps the representatives `kind` asks for. Each representative is
// the vertex's parent, after merging possibly of its own level. Within a level, vertices are numbered so
// that replaying their collapses from the last vertex to the first (multilevel/dag.h) keeps the order
// `earlier` gives, children before parents, otherwise in input order (unmerged levels keep input order:
// their collapses are independent).
// `vertex_order`, if given, receives the input vertex of each multilevel vertex.
MultilevelMesh assemble_multilevel(const Mesh& mesh, const CollapseLevels& levels, MultilevelRepresentatives kind,
                                   std::vector<uint32_t>* vertex_order = nullptr);

// Merges consecutive levels down to `level_count` (merge_level_map); 0 or more than there are: unchanged.
void merge_levels(CollapseLevels& levels, uint32_t level_count);

// The whole path: levels from the collapses, then assembled, then each level's triangles in the order the
// compressed levels code best (by the level's vertex each stands on, turned to start at the corner that
// reaches it; orientation kept); `level_count` > 0 merges consecutive levels down to that many (merge_level_map). Geomorph representatives by default: they make every geomorph's
// ends its two LODs, for up to 2.5% of the binary file (dragon merged to 8 levels; docs/internals.md, "Geomorph
// representatives").
MultilevelMesh build_multilevel(const Mesh& mesh, std::span<const EdgeCollapse> collapses, uint32_t level_count = 0,
                                MultilevelRepresentatives kind = MultilevelRepresentatives::geomorph);

// Level k of `from` levels goes to floor(k * to / from): consecutive levels merge, level 0 and the top stay
// the extremes, and LOD m of the result is LOD min{k : map[k] = m} of the original. to >= from: identity.
std::vector<uint32_t> merge_level_map(uint32_t from, uint32_t to);

}  // namespace pms
