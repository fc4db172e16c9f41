// Small valid hierarchies built by hand or by rule, for the pm-layer tests.
#pragma once
#include <functional>

#include "spm/hierarchy.h"

namespace pms::test {

// Three base vertices (one base face) and three splits:
//   root 0 -> 3, 4;  root 1 -> 5, 6;  node 4 -> 7, 8;  root 2 stays a leaf.
// With normals and colors when `attributes`. compute_ids() has run.
Hierarchy make_small_hierarchy(bool attributes = true);

// A forest grown breadth-first from `roots` roots: a node splits when `split(tree, depth,
// leftmost)` says so (`leftmost`: on its tree's first-child path). Every section is valid (cut
// vertices are leaves of the next tree, so roots >= 2). compute_ids() has NOT run: the rule may
// grow trees deeper than ids allow.
using SplitRule = std::function<bool(uint32_t tree, int depth, bool leftmost)>;
Hierarchy make_forest(uint32_t roots, const SplitRule& split);

}  // namespace pms::test
