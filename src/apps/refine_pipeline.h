// View-independent refinement of a complete model: the first K vsplits in stream (PM) order.
#pragma once
#include <cstdint>

#include "io/mesh.h"
#include "pm/pm.h"

namespace pms::app {

// refine_in_stream_order() as a Mesh (with normals/colors) for the exporters.
Mesh refine_first_splits(const ModelView& model, uint64_t k);

}  // namespace pms::app
