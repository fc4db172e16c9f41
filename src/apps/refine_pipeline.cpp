#include "apps/refine_pipeline.h"

#include "spm/adapt.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/stream_order.h"

namespace pms::app {

Mesh refine_first_splits(const ModelData& model, uint64_t k) { return to_mesh(refine_in_stream_order(model, k)); }

Mesh refine_for_camera(const ModelData& model, const Camera& camera, float tolerance_px, uint64_t* vsplits) {
  ViewRefineResult result = refine_for_view(model, camera, tolerance_px);
  if (vsplits) *vsplits = result.mesh.slots.size() - model.root_count;
  return to_mesh(std::move(result.mesh));
}

}  // namespace pms::app
