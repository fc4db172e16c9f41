// The one place a server's streaming modes are chosen: a new mode adds its case here and its own files.
#include "server/session_mode.h"

#include "server/dag_mode.h"
#include "server/sender_driven_mode.h"
#include "server/view_independent_mode.h"

namespace pms::server {

std::unique_ptr<SessionMode> open_session_mode(const protocol::OpenHeader& open, protocol::Frame& open_frame,
                                               const ModeContext& context) {
  switch (open.mode) {
    case protocol::StreamMode::sender_driven:
    case protocol::StreamMode::sender_plain:
      return std::make_unique<SenderDrivenMode>(open, open_frame, context);
    case protocol::StreamMode::view_independent:
      return std::make_unique<ViewIndependentMode>(open, context);
    case protocol::StreamMode::dag:
      return std::make_unique<DagSessionMode>(open, open_frame, context);
  }
  throw protocol::ProtocolError(protocol::ErrorCode::bad_message, "OPEN: a mode this server does not stream");
}

void LatestView::record(const protocol::View& view, const ModelData& model) {
  criteria = make_criteria(make_view(view.camera, model.bbox_min, model.bbox_max), view.tolerance);
  frame = view.frame;
  pending = true;
  restart = true;
}

Importance LatestView::importance(const std::vector<NodeCriteria>& per_node) const {
  return [this, &per_node](uint32_t node) { return refinement_priority(criteria, per_node[node]); };
}

}  // namespace pms::server
