#include "apps/refine_pipeline.h"

#include "refine/stream_order.h"

namespace pms::app {

Mesh refine_first_splits(const ModelView& model, uint64_t k) {
  MeshArrays arrays = refine_in_stream_order(model, k);
  Mesh out;
  out.positions = std::move(arrays.positions);
  out.normals = std::move(arrays.normals);
  out.colors = std::move(arrays.colors);
  out.indices = std::move(arrays.indices);
  return out;
}

}  // namespace pms::app
