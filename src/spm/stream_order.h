// View-independent refinement of a complete model: the first K vsplits in stream (PM) order,
// applied through the selective-refinement engine (the `vi` baseline and `refine --splits K`).
#pragma once
#include <cstdint>

#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"

namespace pms {

// Applies split_order[0, k) (k clamped to the total) and returns the resulting mesh.
MeshArrays refine_in_stream_order(const ModelData& model, uint64_t k);

}  // namespace pms
