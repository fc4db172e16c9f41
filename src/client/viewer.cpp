// What every Viewer shares, in the browser's core too (the native factory is open_viewer.cpp).
#include "client/viewer.h"

namespace pms::client {

Mesh to_mesh(MeshArrays&& arrays) {
  Mesh out;
  out.positions = std::move(arrays.positions);
  out.normals = std::move(arrays.normals);
  out.colors = std::move(arrays.colors);
  out.indices = std::move(arrays.indices);
  return out;
}

Mesh current_mesh(SelectiveRefinement& refinement) {
  MeshArrays arrays;
  refinement.extract(arrays);
  return to_mesh(std::move(arrays));
}

const MeshBuffers& Viewer::buffers() {
  if (const SelectiveRefinement* shown = refinement()) {
    update_buffers(*shown, buffers_);
  } else {
    update_buffers(mesh(), buffers_);
  }
  return buffers_;
}

}  // namespace pms::client
