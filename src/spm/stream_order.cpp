#include "spm/stream_order.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "spm/hierarchy.h"
#include "spm/selective_mesh.h"
#include "spm/split_record.h"
#include "spm/vertex_hierarchy.h"

namespace pms {

MeshArrays refine_in_stream_order(const ModelData& model, uint64_t k) {
  VertexHierarchy hierarchy = VertexHierarchy::from_model(model);
  hierarchy.reserve(model.node_count());
  SelectiveMesh mesh(hierarchy, model.base_faces);
  k = std::min<uint64_t>(k, model.split_order.size());
  for (uint64_t i = 0; i < k; ++i) {
    const uint32_t node = model.split_order[i];
    hierarchy.add_split(split_record(model, node));
    // In stream order every split's ancestors and cut-vertex splits came earlier.
    if (!mesh.vsplit(hierarchy.find(model.id(node))).done)
      fail("", "split " + std::to_string(i) + " of the stream order needs a later split first");
  }
  MeshArrays arrays;
  mesh.extract(arrays);
  return arrays;
}

}  // namespace pms
