// What every Viewer shares, in the browser's core too (the native factory is open_viewer.cpp).
#include "client/viewer.h"

#include "protocol/stream_mode.h"

namespace pms::client {

std::string viewer_mode_names() { return protocol::mode_names() + ", receiver, multilevel"; }

ViewerReport opening_report() {
  ViewerReport report;
  report.opening = true;
  report.satisfied = false;
  return report;
}

Mesh to_mesh(MeshArrays&& arrays) {
  Mesh out;
  out.positions = std::move(arrays.positions);
  out.normals = std::move(arrays.normals);
  out.colors = std::move(arrays.colors);
  out.indices = std::move(arrays.indices);
  return out;
}

Mesh current_mesh(const SelectiveRefinement& refinement) {
  MeshArrays arrays;
  refinement.extract(arrays);
  return to_mesh(std::move(arrays));
}

bool Viewer::in_motion() const {
  const SelectiveRefinement* shown = refinement();
  return shown && shown->geomorphs().morphing() > 0;
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
