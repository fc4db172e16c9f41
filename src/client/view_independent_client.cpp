#include "client/view_independent_client.h"

namespace pms::client {

void ViewIndependentClient::frame(const Camera& camera, ClientSession& session, ViewRequests& server,
                                  FrameReport& report) {
  report.vsplits = server.request_view(
      camera, [this, &session](const protocol::VSplits& batch) { on_batch(batch, session); }, report);
}

void ViewIndependentClient::on_batch(const protocol::VSplits& batch, ClientSession& session) {
  // PM order: a split's ancestors and cut-vertex splits came earlier, so it can be made now.
  session.apply_as_they_come(batch, "the packets are not in PM order");
}

}  // namespace pms::client
