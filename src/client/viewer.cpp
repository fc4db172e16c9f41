// What every Viewer shares, in the browser's core too (the native factory is open_viewer.cpp).
#include "client/viewer.h"

#include <cmath>

#include "common/error.h"
#include "protocol/client_messages.h"
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

ViewerReport Viewer::frame(const Camera& camera) {
  if (const char* problem = camera_problem(camera)) {
    ViewerReport report = last_;
    report.received = report.up_bytes = report.down_bytes = 0;  // this frame's: none
    report.latency_ms = 0;
    report.details = nlohmann::json::object();
    report.refused = std::string("camera: ") + problem;
    return report;
  }
  last_ = frame_view(camera);
  return last_;
}

void Viewer::tune(const ViewerTuning& tuning) {
  if (tuning.tolerance && !(*tuning.tolerance >= 0 && std::isfinite(*tuning.tolerance)))
    fail("tolerance", "must be a finite number >= 0");
  if (tuning.dag_max_ops && (*tuning.dag_max_ops == 0 || *tuning.dag_max_ops > protocol::kMaxDagOps))
    fail("dag.maxOps", "must be in 1.." + std::to_string(protocol::kMaxDagOps));
  if (tuning.dag_budget && *tuning.dag_budget > protocol::kMaxDagBudget)
    fail("dag.budget", "must be at most " + std::to_string(protocol::kMaxDagBudget));
  retune(tuning);
}

void Viewer::retune(const ViewerTuning&) { fail("tune", "this viewer's options are fixed: open a new one"); }

bool Viewer::in_motion() const {
  const SelectiveRefinement* shown = refinement();
  return shown && (shown->geomorphs().morphing() > 0 || !shown->at_rest());
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
