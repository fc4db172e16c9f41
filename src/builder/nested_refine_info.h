// Nested refinement info (spm/nested_info.h): once the forest is built, each node's bounds are
// rounded up, top down, to an entry of the lattice below its parent's final bounds, so that a split record
// codes a child's info as a few entry numbers. Its cone axis first moves to the coarser grid of own axes
// (kAxisSnapBits), with its cone widened and (mu, delta) re-expressed about the moved axis. Every value only
// grows, so every bound still holds: τ keeps its meaning.
#pragma once
#include "builder/simplify.h"

namespace pms {

// Rewrites forest.info in place (roots and nodes that never refine keep theirs). Before packing, so that
// the packed order (by each parent's deviation) is that of the values every mode sees.
void nest_refine_info(CollapseForest& forest);

}  // namespace pms
