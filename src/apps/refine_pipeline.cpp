#include "apps/refine_pipeline.h"

#include <algorithm>

#include "common/error.h"
#include "refine/refine.h"

namespace pms::app {

Mesh refine_first_splits(const ModelView& model, uint64_t k) {
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  hierarchy.reserve(model.node_count());
  SelectiveMesh mesh(hierarchy, model.base_faces);
  k = std::min<uint64_t>(k, model.split_order.size());
  for (uint64_t i = 0; i < k; ++i) {
    const uint32_t node = model.split_order[i];
    hierarchy.add_split(split_record(model, node));
    const VSplitResult result = mesh.vsplit(hierarchy.find(model.id(node)));
    // In stream order every split's ancestors and cut-vertex splits came earlier.
    if (!result.done) fail("", "split " + std::to_string(i) + " of the stream order needs a later split first");
  }
  MeshArrays arrays;
  mesh.extract(arrays);
  Mesh out;
  out.positions = std::move(arrays.positions);
  out.normals = std::move(arrays.normals);
  out.colors = std::move(arrays.colors);
  out.indices = std::move(arrays.indices);
  return out;
}

}  // namespace pms::app
