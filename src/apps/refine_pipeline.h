// View-independent refinement of a complete model: the first K vsplits in stream (PM) order.
#pragma once
#include <cstdint>

#include "io/mesh.h"
#include "pm/pm.h"

namespace pms::app {

// Applies split_order[0, k) through the selective-refinement engine (k is clamped to the total)
// and returns the resulting mesh with its normals/colors.
Mesh refine_first_splits(const ModelView& model, uint64_t k);

}  // namespace pms::app
