// Local refinement of a progressive multilevel mesh (gueziec et al. 1999, "Local refinement", Fig. 15): a
// status per collapse (split or collapsed) kept consistent with the DAG by split and collapse constraint
// counts in hash tables keyed by vertex, and a topological sort that turns any set of wanted vertices into
// the consistent subset of vertex splits that brings them in.
#pragma once
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "io/mesh.h"
#include "multilevel/dag.h"
#include "multilevel/mesh.h"

namespace pms {

class MultilevelRefinement {
 public:
  // The coarsest LOD: every collapse done. The DAG must outlive the refinement.
  explicit MultilevelRefinement(const MultilevelDag& dag);

  // Top-level vertices are always in; a node is in once split.
  bool is_split(uint32_t v) const { return split_[v] != 0; }
  std::span<const uint8_t> split_flags() const { return split_; }
  uint32_t split_count() const { return split_count_; }

  // Paper: a split constraint of v is a prerequisite of v still collapsed; a collapse constraint is a
  // dependent of v split. A split needs no split constraints, a collapse no collapse constraints.
  uint32_t split_constraints(uint32_t v) const { return count(split_constraints_, v); }
  uint32_t collapse_constraints(uint32_t v) const { return count(collapse_constraints_, v); }
  bool can_split(uint32_t v) const;
  bool can_collapse(uint32_t v) const;
  // pms::Error when the DAG forbids it (or v is not a node, or already in that status).
  void split(uint32_t v);
  void collapse(uint32_t v);

  // Fig. 15: afterwards the split vertices are exactly `wanted` (top-level vertices and repeats are
  // ignored) and everything they need, transitively. What no wanted vertex needs is collapsed, dependents
  // first; what is missing is split, prerequisites first, both in the order a topological sort of that
  // part of the DAG driven by the constraint counts gives. Returns the splits in the order made.
  struct Changes {
    std::vector<uint32_t> splits, collapses;
  };
  Changes refine_to(std::span<const uint32_t> wanted);

  // The tables' entries (only non-zero counts are stored) and their bytes, for the memory report.
  size_t constraint_entries() const { return split_constraints_.size() + collapse_constraints_.size(); }
  uint64_t memory_bytes() const;

 private:
  using CountTable = std::unordered_map<uint32_t, uint32_t>;
  static uint32_t count(const CountTable& table, uint32_t v);
  static void add(CountTable& table, uint32_t v, int delta);
  // Marks `wanted` and its prerequisites, transitively (1 per vertex in `mark`).
  void close_over_prerequisites(std::span<const uint32_t> wanted, std::vector<uint8_t>& mark) const;
  // Splits (or collapses) every node `kept` says should be (or not be) split, in a topological order.
  void change_status(bool splitting, const std::vector<uint8_t>& kept, std::vector<uint32_t>& done);

  const MultilevelDag& dag_;
  std::vector<uint8_t> split_;  // per vertex
  uint32_t split_count_ = 0;    // nodes split
  CountTable split_constraints_, collapse_constraints_;
};

// The mesh of a refinement: the top-level vertices and the split ones (in multilevel order), and the
// triangles whose remover is in (the others of a level only when the whole LOD of that level is), each
// corner drawn by its first representative that is in. pms::Error if a corner has none (it cannot for a
// refinement the DAG allowed).
struct LocalMesh {
  Mesh mesh;
  std::vector<uint32_t> vertex;  // per output vertex, its multilevel number
};
LocalMesh local_mesh(const MultilevelMesh& mesh, const MultilevelDag& dag, const MultilevelRefinement& refinement);

}  // namespace pms
