// The simplification stage shared by the balanced and the greedy orders: every accepted half-edge
// collapse goes through CollapseRecorder, which keeps the vertex hierarchy (temporary numbering:
// leaves = input vertices, then one internal node per collapse) and its refinement info.
#pragma once
#include <cstdint>
#include <vector>

#include "builder/build.h"
#include "builder/captured_round.h"
#include "builder/collapse_mesh.h"
#include "builder/refinement_info.h"
#include "common/background_loop.h"
#include "spm/refine_info.h"

namespace pms {

// The forest in collapse order. Internal node k (k = 0..collapses-1) has temporary index
// leaf_count + k; its children are child_t[k] (removed vertex) and child_u[k] (survivor).
struct CollapseForest {
  uint32_t leaf_count = 0;
  std::vector<uint32_t> child_t, child_u;
  std::vector<uint32_t> cut_l, cut_r;   // fundamental cut leaves (input vertices), UINT32_MAX if absent
  std::vector<uint32_t> root_node;      // temporary node of each base vertex
  std::vector<uint32_t> base_faces;     // 3 per base face, indices into root_node
  std::vector<RefineInfo> info;         // per temporary node
  std::vector<uint32_t> survivor_leaf;  // per temporary node: the leaf whose position/attributes it carries

  uint32_t node_count() const { return leaf_count + uint32_t(child_t.size()); }
};

class CollapseRecorder {
 public:
  CollapseRecorder(const Mesh& mesh, CollapseMesh& collapse_mesh, Deviation deviation);

  // Collapses t into u (check_collapse() must have accepted it) and records the new node. Its
  // refinement info is computed after the next end_round() or flush().
  void apply(uint32_t t, uint32_t u, const CollapseSite& site);
  // Ends a round: the collapses applied since the last one (independent: no vertex in two of them)
  // get their refinement info computed, a big round's on another thread while the caller goes on
  // collapsing. The working mesh may change and be compacted meanwhile.
  void end_round();
  // end_round(), and returns once every collapse's refinement info is there.
  void flush();
  // Height of the subtree whose root is vertex v's current node (0 for an input vertex).
  uint32_t height(uint32_t v) const { return current_[v].height; }
  uint64_t collapses() const { return forest_.child_t.size(); }

  CollapseForest finish();

  // Renumbers the working mesh's live vertices (CollapseMesh::compact) and every per-vertex array
  // here with it; ends the round first. new_index as compact() returns it.
  void compact(std::vector<uint32_t>& new_index);

 private:
  CollapseMesh& mesh_;
  CollapseForest forest_;
  RefinementInfoBuilder refinement_;
  // What a collapse reads about its two vertices, in one place: the collapse loop visits vertices
  // in cost order, i.e. at random, and per-node arrays would cost a cache miss each.
  struct CurrentNode {
    uint32_t node;           // temporary node the working-mesh vertex carries now
    uint32_t height;         // of that node's subtree
    uint32_t survivor_leaf;  // of that node
  };
  std::vector<CurrentNode> current_;              // per working-mesh vertex
  std::vector<CapturedRound::Collapse> pending_;  // the round's collapses so far
  CapturedRound computing_round_;
  BackgroundLoop computing_;
};

// kim-lee-kobbelt §6.2: rounds of independent cheapest collapses, cost weighted by subtree height.
CollapseForest simplify_balanced(const Mesh& mesh, const BuildOptions& options);
// Hoppe 1996: one collapse at a time in quadric-error order (the view-independent baseline).
CollapseForest simplify_greedy(const Mesh& mesh, const BuildOptions& options);

// Best target u for removing t (lowest quadric error over t's neighbours), ignoring validity.
struct Candidate {
  double cost;
  uint32_t t, u;
};

}  // namespace pms
