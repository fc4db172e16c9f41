// Refinement of a complete model for the CLI: the first K vsplits in stream order (view-independent), or
// the mesh of one view at a screen-space tolerance (view-dependent, Hoppe 1997 criteria).
#pragma once
#include <cstdint>

#include "client/viewer.h"
#include "common/camera.h"
#include "io/mesh.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"

namespace pms::app {

using client::to_mesh;  // the refine layer's flat arrays as io's Mesh (for the exporters)

// refine_in_stream_order() as a Mesh (with normals/colors) for the exporters.
Mesh refine_first_splits(const ModelData& model, uint64_t k);

// refine_for_view(): from the base mesh to the converged mesh of `camera` at `tolerance_px`;
// `vsplits` (if given) receives how many vsplits the mesh holds (its vertices minus the base's).
Mesh refine_for_camera(const ModelData& model, const Camera& camera, float tolerance_px, uint64_t* vsplits = nullptr);

}  // namespace pms::app
